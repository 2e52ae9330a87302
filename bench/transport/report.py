#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Turns sim_bench's CSV into the report: a Markdown table (mean with a 95 % confidence interval
across runs), a JSON file with every figure, and plots in the style of the SIM paper's figures
(whiskers min-max, a dot at the mean, a long tick at p95, a short dashed tick at p99), linear and
log scale, as PNG and SVG.

    report.py RESULTS.csv [--out DIR] [--title TEXT]

RESULTS_extra.csv next to the CSV (written by sim_bench) adds context switches, UDP datagrams and
the data path of each run when present. Only the Python standard library and matplotlib.
"""
import argparse
import csv
import json
import math
import os
import statistics
import sys
from collections import defaultdict

ORDER = ["memcpy", "sim-poll", "sim-poll-described", "sim-block", "sim-zero", "sim-adaptive", "sim-zero-adaptive", "iceoryx",
         "fastdds", "cyclone"]
PEERS = ["iceoryx", "fastdds", "cyclone"]
LABEL = {
    "memcpy": "memcpy floor",
    "sim-poll": "SIM poll (copy)",
    "sim-poll-described": "SIM poll, sensor description",
    "sim-block": "SIM block (copy)",
    "sim-zero": "SIM borrow (zero-copy)",
    "sim-adaptive": "SIM adaptive (copy)",
    "sim-zero-adaptive": "SIM adaptive borrow",
    "iceoryx": "iceoryx 2.0",
    "fastdds": "Fast DDS 2.9",
    "cyclone": "Cyclone DDS 0.10",
}
METRICS = ["min_us", "mean_us", "p50_us", "p95_us", "p99_us", "p999_us", "max_us", "std_us"]
# Two-sided 95 % Student t quantiles by degrees of freedom.
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306,
       9: 2.262, 10: 2.228, 15: 2.131, 20: 2.086, 30: 2.042}


def t95(dof):
    if dof <= 0:
        return float("nan")
    best = max(k for k in T95 if k <= dof)
    return T95[best] if dof <= 30 else 1.96


def number(text):
    try:
        return float(text)
    except ValueError:
        return float("nan")


def load(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            row = {"transport": r["transport"], "payload_bytes": int(r["payload_bytes"]),
                   "readers": int(r["readers"]), "run": int(r["run"])}
            for key in METRICS + ["writer_cpu_s", "reader_cpu_s"]:
                row[key] = number(r[key])
            for key in ["received", "skipped", "lost"]:
                row[key] = int(r[key])
            rows.append(row)
    extra_path = path[:-4] + "_extra.csv" if path.endswith(".csv") else path + "_extra.csv"
    if os.path.exists(extra_path):
        extra = {}
        with open(extra_path, newline="") as f:
            for r in csv.DictReader(f):
                extra[(r["transport"], int(r["payload_bytes"]), int(r["readers"]), int(r["run"]))] = r
        for row in rows:
            e = extra.get((row["transport"], row["payload_bytes"], row["readers"], row["run"]))
            if e:
                row["published"] = int(e["published"])
                row["context_switches_writer"] = int(e["writer_nvcsw"]) + int(e["writer_nivcsw"])
                row["context_switches_readers"] = int(e["reader_nvcsw"]) + int(e["reader_nivcsw"])
                row["udp_datagrams"] = int(e["udp_datagrams"])
                row["path"] = e["path"]
                row["status"] = e["status"]
    return rows


def aggregate(rows):
    groups = defaultdict(list)
    for r in rows:
        if r.get("status", "ok") == "failed" or math.isnan(r["mean_us"]):
            continue
        groups[(r["transport"], r["payload_bytes"], r["readers"])].append(r)
    out = []
    for (transport, payload, readers), runs in groups.items():
        a = {"transport": transport, "payload_bytes": payload, "readers": readers, "runs": len(runs)}
        for key in METRICS + ["writer_cpu_s", "reader_cpu_s"]:
            values = [r[key] for r in runs]
            a[key] = statistics.fmean(values)
        means = [r["mean_us"] for r in runs]
        half = t95(len(means) - 1) * statistics.stdev(means) / math.sqrt(len(means)) if len(means) > 1 else float("nan")
        a["mean_ci95_us"] = [a["mean_us"] - half, a["mean_us"] + half] if not math.isnan(half) else None
        # Standard errors of the run means of mean and p99, for the SIM-vs-peer ratios.
        for key in ["mean_us", "p99_us"]:
            values = [r[key] for r in runs]
            a[key + "_se"] = statistics.stdev(values) / math.sqrt(len(values)) if len(values) > 1 else float("nan")
        a["min_of_runs_us"] = min(r["min_us"] for r in runs)
        a["max_of_runs_us"] = max(r["max_us"] for r in runs)
        for key in ["received", "skipped", "lost"]:
            a[key] = sum(r[key] for r in runs)
        for key in ["context_switches_writer", "context_switches_readers", "udp_datagrams"]:
            if all(key in r for r in runs):
                a[key] = sum(r[key] for r in runs) / len(runs)
        paths = sorted({r.get("path", "-") for r in runs})
        a["path"] = ",".join(paths)
        out.append(a)
    out.sort(key=lambda a: (a["readers"], a["payload_bytes"], ORDER.index(a["transport"]) if a["transport"] in ORDER else 99))
    return out


def fmt(v, digits=0):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:,.{digits}f}"


def ci_text(a):
    if a["mean_ci95_us"] is None:
        return fmt(a["mean_us"], 1)
    lo, hi = a["mean_ci95_us"]
    return f"{a['mean_us']:,.1f} [{lo:,.1f}, {hi:,.1f}]"


def finite(value):
    """NaN (a run without samples) becomes null, so the JSON stays valid JSON."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite(v) for v in value]
    return value


def lookup(agg):
    return {(a["transport"], a["payload_bytes"], a["readers"]): a for a in agg}


def floor_of(index, payload):
    # The floor is measured once per payload (readers = 1); it is the same for every fan-out.
    return index.get(("memcpy", payload, 1))


def goals(agg):
    """The goals of issue 5, checked against the numbers; each line says met or missed."""
    index = lookup(agg)
    configs = sorted({(a["payload_bytes"], a["readers"]) for a in agg if a["transport"] != "memcpy"})
    lines = []
    for name in ["sim-block", "sim-zero", "sim-poll"]:
        misses = []
        checked = 0
        for payload, readers in configs:
            sim = index.get((name, payload, readers))
            if sim is None:
                continue
            for peer in PEERS:
                p = index.get((peer, payload, readers))
                if p is None:
                    continue
                checked += 1
                if not (sim["mean_us"] < p["mean_us"] and sim["p99_us"] < p["p99_us"]):
                    misses.append(f"{payload:,} B {readers}R vs {peer}: mean {sim['mean_us']:,.0f} vs "
                                  f"{p['mean_us']:,.0f} µs, p99 {sim['p99_us']:,.0f} vs {p['p99_us']:,.0f} µs")
        if checked:
            verdict = "met" if not misses else f"missed in {len(misses)} of {checked} comparisons"
            lines.append(f"- {LABEL[name]}: mean and p99 below every peer — **{verdict}**")
            lines += [f"  - {m}" for m in misses]
    for payload in sorted({p for p, _ in configs}):
        floor = floor_of(index, payload)
        if floor is None or payload < 500_000:
            continue
        for name in ["sim-block", "sim-poll"]:
            for readers in sorted({r for p, r in configs if p == payload}):
                sim = index.get((name, payload, readers))
                if sim is None:
                    continue
                ratio = sim["mean_us"] / floor["mean_us"]
                median_ratio = sim["p50_us"] / floor["p50_us"]
                verdict = "met" if ratio <= 1.25 else "missed"
                lines.append(f"- {LABEL[name]} {payload:,} B {readers}R: mean {sim['mean_us']:,.0f} µs = "
                             f"{ratio:.2f}× the memcpy floor ({floor['mean_us']:,.0f} µs); goal ≤ 1.25× — **{verdict}** "
                             f"(medians: {sim['p50_us']:,.0f} vs {floor['p50_us']:,.0f} µs, {median_ratio:.2f}×)")
    for payload, readers in configs:
        z, i = index.get(("sim-zero", payload, readers)), index.get(("iceoryx", payload, readers))
        if z and i:
            d = z["mean_us"] - i["mean_us"]
            verdict = "met" if d <= 5 else "missed"
            lines.append(f"- SIM borrow vs iceoryx {payload:,} B {readers}R: {z['mean_us']:,.1f} vs "
                         f"{i['mean_us']:,.1f} µs (Δ {d:+,.1f} µs); goal within a few µs — **{verdict}**")
    for payload, readers in configs:
        b, p = index.get(("sim-block", payload, readers)), index.get(("sim-poll", payload, readers))
        if b and p:
            lines.append(f"- Blocking vs polling reader {payload:,} B {readers}R: p99 {b['p99_us']:,.0f} µs; "
                         f"reader CPU {b['reader_cpu_s']:.2f} s vs {p['reader_cpu_s']:.2f} s per run (all readers)")
    lost = [(a["transport"], a["payload_bytes"], a["readers"], a["lost"]) for a in agg
            if a["transport"].startswith("sim-") and a["lost"] > 0]
    lines.append("- SIM frames lost (not skipped by design): " +
                 ("**none**" if not lost else "; ".join(f"{t} {p:,} B {r}R: {n}" for t, p, r, n in lost)))
    return lines


def ratio_text(sim, peer, key):
    """SIM / peer for `key` with a 95 % interval (delta method on the two run means; below 1: SIM ahead)."""
    a, b = sim[key], peer[key]
    if not b:
        return "–"
    r = a / b
    se_a, se_b = sim.get(key + "_se", float("nan")), peer.get(key + "_se", float("nan"))
    if math.isnan(se_a) or math.isnan(se_b) or a == 0:
        return f"{r:.2f}"
    dof = min(sim["runs"], peer["runs"]) - 1
    half = t95(dof) * r * math.sqrt((se_a / a) ** 2 + (se_b / b) ** 2)
    return f"{r:.2f} [{max(0.0, r - half):.2f}, {r + half:.2f}]"


def ratios(agg):
    """Every SIM transport against every peer: mean and p99 ratios with their intervals."""
    index = lookup(agg)
    configs = sorted({(a["payload_bytes"], a["readers"]) for a in agg if a["transport"] != "memcpy"},
                     key=lambda c: (c[1], c[0]))
    lines = ["| payload | readers | SIM | peer | mean ratio [95 % CI] | p99 ratio [95 % CI] |",
             "|---|---|---|---|---|---|"]
    for payload, readers in configs:
        for name in [t for t in ORDER if t.startswith("sim-")]:
            sim = index.get((name, payload, readers))
            if sim is None:
                continue
            for peer_name in PEERS:
                peer = index.get((peer_name, payload, readers))
                if peer is None:
                    continue
                lines.append(f"| {payload:,} | {readers} | {LABEL[name]} | {LABEL[peer_name]} | "
                             f"{ratio_text(sim, peer, 'mean_us')} | {ratio_text(sim, peer, 'p99_us')} |")
    return lines if len(lines) > 2 else []


def markdown(agg, title, command):
    index = lookup(agg)
    transports = [t for t in ORDER if any(a["transport"] == t for a in agg)]
    configs = sorted({(a["payload_bytes"], a["readers"]) for a in agg if a["transport"] != "memcpy"},
                     key=lambda c: (c[1], c[0]))
    out = [f"# {title}", ""]
    if command:
        out += ["Command:", "", "```", command, "```", ""]
    runs = max((a["runs"] for a in agg), default=0)
    out += [f"Mean latency in µs with its 95 % confidence interval across runs (n = {runs}), then p99 "
            "(mean of the runs' p99). Latency: writer stamp immediately before publish → reader holds "
            "the whole payload.", ""]
    head = "| payload | readers | " + " | ".join(LABEL[t] for t in transports) + " |"
    out += [head, "|" + "---|" * (2 + len(transports))]
    for payload, readers in configs:
        cells = []
        for t in transports:
            a = floor_of(index, payload) if t == "memcpy" else index.get((t, payload, readers))
            cells.append("–" if a is None else f"{ci_text(a)} / {fmt(a['p99_us'])}")
        out.append(f"| {payload:,} | {readers} | " + " | ".join(cells) + " |")
    out += ["", "## Every figure (means over runs; received/skipped/lost summed over runs and readers)", "",
            "| transport | payload | R | min | mean [95 % CI] | p50 | p95 | p99 | p99.9 | max | std | "
            "received | skipped | lost | writer CPU s | readers CPU s | ctx sw W | ctx sw R | UDP dgrams | path |",
            "|" + "---|" * 20]
    for payload, readers in configs:
        for t in transports:
            a = floor_of(index, payload) if t == "memcpy" else index.get((t, payload, readers))
            if a is None:
                continue
            out.append(
                f"| {t} | {payload:,} | {readers} | {fmt(a['min_us'], 1)} | {ci_text(a)} | {fmt(a['p50_us'], 1)} | "
                f"{fmt(a['p95_us'], 1)} | {fmt(a['p99_us'], 1)} | {fmt(a['p999_us'], 1)} | {fmt(a['max_us'], 1)} | "
                f"{fmt(a['std_us'], 1)} | {a['received']:,} | {a['skipped']:,} | {a['lost']:,} | "
                f"{a['writer_cpu_s']:.3f} | {a['reader_cpu_s']:.3f} | {fmt(a.get('context_switches_writer'))} | "
                f"{fmt(a.get('context_switches_readers'))} | {fmt(a.get('udp_datagrams'))} | {a.get('path', '-')} |")
    ratio_lines = ratios(agg)
    if ratio_lines:
        out += ["", "## SIM against each peer (ratio of SIM to peer; below 1: SIM is ahead; an interval "
                "that contains 1: no clear difference)", ""] + ratio_lines
    out += ["", "## Goals of issue 5, checked against these numbers", ""] + goals(agg) + [""]
    return "\n".join(out)


def plot(agg, out_dir, stem):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("report.py: this python has no matplotlib: apt-get install python3-matplotlib and run "
              "report.py with /usr/bin/python3; no plots this time.", file=sys.stderr)
        return []
    index = lookup(agg)
    written = []
    payloads = sorted({a["payload_bytes"] for a in agg})
    for readers in sorted({a["readers"] for a in agg if a["transport"] != "memcpy"}):
        for scale in ["linear", "log"]:
            fig, axes = plt.subplots(1, len(payloads), figsize=(4.2 * len(payloads), 4.4), squeeze=False)
            for ax, payload in zip(axes[0], payloads):
                names, entries = [], []
                for t in ORDER:
                    a = floor_of(index, payload) if t == "memcpy" else index.get((t, payload, readers))
                    if a is not None:
                        names.append(LABEL[t])
                        entries.append(a)
                for x, a in enumerate(entries):
                    ax.vlines(x, a["min_of_runs_us"], a["max_of_runs_us"], color="0.35", linewidth=1)
                    ax.hlines([a["min_of_runs_us"], a["max_of_runs_us"]], x - 0.12, x + 0.12, color="0.35", linewidth=1)
                    ax.hlines(a["p95_us"], x - 0.3, x + 0.3, color="tab:blue", linewidth=2)
                    ax.hlines(a["p99_us"], x - 0.18, x + 0.18, color="tab:red", linewidth=1.5, linestyles="dashed")
                    ax.plot(x, a["mean_us"], "o", color="black", markersize=5)
                ax.set_xticks(range(len(names)))
                ax.set_xticklabels(names, rotation=40, ha="right", fontsize=8)
                ax.set_yscale(scale)
                ax.set_title(f"{payload:,} B, 1W→{readers}R", fontsize=10)
                ax.set_ylabel("latency (µs)")
                ax.grid(axis="y", alpha=0.3, which="both" if scale == "log" else "major")
            fig.suptitle("Transport latency: whiskers min–max, dot mean, long tick p95, short dashed tick p99",
                         fontsize=10)
            fig.tight_layout()
            for ext in ["png", "svg"]:
                path = os.path.join(out_dir, f"{stem}_{readers}R_{scale}.{ext}")
                fig.savefig(path, dpi=110)
                written.append(path)
            plt.close(fig)
    return written


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", help="sim_bench --csv output")
    parser.add_argument("--out", help="folder for the table, JSON and plots (default: the CSV's folder)")
    parser.add_argument("--title", default="SIM transport benchmark")
    parser.add_argument("--command", default="", help="the sim_bench command line, quoted in the table")
    args = parser.parse_args()
    if not os.path.exists(args.csv):
        print(f"report.py: {args.csv} does not exist: run sim_bench --csv {args.csv} first.", file=sys.stderr)
        return 2
    out_dir = args.out or os.path.dirname(os.path.abspath(args.csv))
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.splitext(os.path.basename(args.csv))[0]
    rows = load(args.csv)
    if not rows:
        print(f"report.py: {args.csv} has no rows.", file=sys.stderr)
        return 1
    agg = aggregate(rows)
    md_path = os.path.join(out_dir, f"{stem}.md")
    with open(md_path, "w") as f:
        f.write(markdown(agg, args.title, args.command))
    json_path = os.path.join(out_dir, f"{stem}.json")
    with open(json_path, "w") as f:
        json.dump(finite({"command": args.command, "summary": agg, "runs": rows}), f, indent=1)
    written = [md_path, json_path] + plot(agg, out_dir, stem)
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
