#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The soak test of the whole vehicle (issue 23): scripts/soak.sh builds what it needs and runs this.

    tests/soak/soak.py --build build/release --seconds 120 [--json soak.json] [--seed N]

Seven 1920x1200 bgr8 camera streams at 30 Hz, two replayed LiDAR streams and two live ones on one
port by multicast, readers of every kind, and a chaos loop that kills and restarts readers and
writers (SIGKILL and SIGTERM), replaces a stream's layout and removes dead streams. It checks
continuously and reports at the end as a table and as JSON; exit 0 only if every check passed. What is checked and why it is fair on a loaded machine:
tests/soak/README.md.
"""
import argparse
import ctypes
import json
import os
import queue
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
HESAI = os.path.join(ROOT, "tests", "drivers", "hesai", "data")
VELODYNE = os.path.join(ROOT, "tests", "drivers", "velodyne", "data")
# Two live LiDARs on one UDP port, each joined to its own multicast group, in a network namespace
# of their own (README "Two LiDARs on one port"): soak_multicast.py sends each capture's payloads
# to its group from its own address; each driver must hear only its sensor (other_senders=0).
MULTICAST_PORT = 2368
MULTICAST_FEEDS = (  # group, sender address, capture, program (in the build), calibration
    ("239.255.77.1", "127.0.0.2", os.path.join(HESAI, "pandarxt32_dual.pcap"), "drivers/hesai/sim_lidar_hesai",
     os.path.join(HESAI, "pandarxt32.calibration.csv")),
    ("239.255.77.2", "127.0.0.3", os.path.join(VELODYNE, "vlp16_dual.pcap"),
     "drivers/velodyne/stream/sim_lidar_velodyne", os.path.join(VELODYNE, "VLP16.yaml")),
)
# Counters of a live driver's --summary that say it decoded another sensor's packets.
HEARD_ANOTHER = ("other_senders", "malformed", "wrong_model")
CAMERA_PERIOD_MS = 1000 / 30
LIDAR_PERIOD_MS = 100.0
STOP_GRACE_S = 15  # a process asked to stop with SIGTERM must be gone by then (else: a hang)
SILENCE_S = 20     # a reader that prints nothing for this long hangs
PROGRESS_EVERY_S = 60  # how often a running soak prints one line of progress
# A long-lived reader must get at least this share of the frames it waited for: frames / (frames +
# frames it slept through). Readers take the newest frame, so frames skipped while a reader was
# busy or kept from running (run delay) are by design; a transport that loses every other wake-up
# delivers half (on a quiet machine: a loaded one's run delays excuse many single skipped frames).
DELIVERY_FLOOR = 0.80
# Private memory must be flat: the slope over the run (Theil-Sen, robust to a few steps) may
# not exceed a steady growth of MEMORY_NOISE_KIB over the judged window or MEMORY_SLOPE_KIB_PER_H,
# whichever is larger (so a long run judges tighter: an hour allows ~3.5 MiB of steady growth).
MEMORY_NOISE_KIB = 2048
MEMORY_SLOPE_KIB_PER_H = 3600
MEMORY_EVERY_S = 2.0
# Processes whose private memory swings by tens of MB while they warm up (sim_foxglove: 17-47 MB
# within a minute as clients subscribe and its encoders size their buffers): their slope is
# judged only over a window at least this long (seconds); shorter runs show it.
MEMORY_JUDGED_FROM_S = {"sim_foxglove": 600}
# The faults soak.py --fault can put in (tests/soak/README.md, "Faults"), and the check each
# must turn red.
FAULTS = ("torn", "lost_wakeups", "half_frames", "leak", "stale_region", "broken_recording")

_libc = ctypes.CDLL(None, use_errno=True)


def _die_with_parent():
    """In the child: SIGKILL when the thread that started it ends (the spawner, which lives as
    long as the soak), so nothing is left behind however the soak ends."""
    _libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


class Spawner:
    """Starts every child from one thread that lives as long as the soak: PR_SET_PDEATHSIG fires
    when the starting *thread* ends, so children started by the chaos loop's short threads would
    otherwise die with them."""

    def __init__(self):
        self.requests = queue.Queue()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            make, done = self.requests.get()
            try:
                done.append(make())
            except Exception as e:  # handed back to the caller
                done.append(e)

    def run(self, make):
        done = []
        self.requests.put((make, done))
        while not done:
            time.sleep(0.005)
        if isinstance(done[0], Exception):
            raise done[0]
        return done[0]


class Child:
    """One process of the soak: its JSON lines (stats, violations) read on a thread."""

    def __init__(self, soak, name, argv, long_lived, env=None):
        self.soak, self.name, self.argv, self.long_lived = soak, name, argv, long_lived
        file_name = name.replace("/", "_")
        self.log_path = os.path.join(soak.workdir, f"{file_name}.{len(soak.history.get(name, []))}.log")
        self.log = open(self.log_path, "w")
        self.proc = soak.spawner.run(lambda: subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=self.log, text=True, env=env, preexec_fn=_die_with_parent))
        self.pid = self.proc.pid
        self.started = time.monotonic()
        self.last_line = self.started
        self.stats = None
        self.other = []  # JSON lines that are neither stats nor violations (sim_foxglove's port)
        self.summary = None  # a live driver's --summary line on exit, as {key: value}
        self.signalled = None
        self.handled = False  # whether it had its handler for the signal it was sent
        self.ended_reported = False
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.proc.stdout:
            self.last_line = time.monotonic()
            if line.startswith("summary "):
                self.summary = dict(kv.split("=", 1) for kv in line.split()[1:] if "=" in kv)
                continue
            try:
                record = json.loads(line)
            except ValueError:
                continue
            if record.get("kind") == "violation":
                self.soak.violation(self.name, record)
            elif record.get("kind") == "publish_gap":
                with self.soak.lock:
                    self.soak.publish_gaps.append(record)
            elif record.get("kind") == "stats":
                self.stats = record
            else:
                self.other.append(record)

    def alive(self):
        return self.proc.poll() is None

    def handles(self, sig):
        """Whether the process has installed a handler for `sig` (SigCgt in /proc/PID/status)."""
        try:
            for line in open(f"/proc/{self.pid}/status"):
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (sig - 1) & 1)
        except OSError:
            pass
        return False

    def send(self, sig):
        self.signalled = sig
        self.handled = self.handles(sig)
        try:
            self.proc.send_signal(sig)
        except ProcessLookupError:
            pass

    def stop(self, sig=signal.SIGTERM):
        """Signals it and waits; the exit code, or None if it hung (then it is killed)."""
        self.send(sig)
        try:
            code = self.proc.wait(STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            code = None
        self.reader.join(5)
        self.log.close()
        return code

    def stderr_tail(self):
        if not self.log.closed:
            self.log.flush()
        try:
            with open(self.log_path, errors="replace") as f:
                return f.read()[-400:].strip()
        except FileNotFoundError:  # the soak is ending and has removed its folder
            return ""


def classify_stalls(violations, publish_gaps):
    """Tells a writer's (or the whole machine's) stall from a reader's lost wake-up, by the soak
    writer's own publish_gap lines. A "missed" stall is a "writer_stall" when, without the part of
    it the writer spent paused, it would have been within its allowance, and the pause was
      - inside the writer's commit (in_commit: the frame became readable in it, but its wake-up
        comes only as the commit returns, so every sleeping reader waited for the writer), or
      - between two commits, while another reader process stalled on the same stream at the same
        moment (nothing ran: the whole machine paused).
    A stall of one reader while the writer published on time, or of every reader while the writer
    published on time (its wake-up failed them all), stays "missed". Changes the violations in
    place; returns how many it reclassified."""
    def window(v):
        return v.get("readable_ns"), v.get("end_ns")
    missed = [v for v in violations if v.get("what") == "missed" and None not in window(v)]
    changed = 0
    for v in missed:
        start, end = window(v)
        others = {w["process"] for w in missed if w is not v and w["stream"] == v["stream"] and
                  w["process"] != v["process"] and w["readable_ns"] < end and w["end_ns"] > start}
        paused_ms = max([(min(end, g["to_ns"]) - max(start, g["from_ns"])) / 1e6 for g in publish_gaps
                         if g["stream"] == v["stream"] and (others or g.get("in_commit"))] + [0.0])
        allowance_ms = min(2 * v.get("period_ms", 0), CAMERA_PERIOD_MS * 2)
        if paused_ms > 0 and v.get("stall_ms", 0) - paused_ms <= allowance_ms:
            changed += 1
            v["what"] = "writer_stall"
            v["why"] = (f"the writer was paused for {paused_ms:.1f} ms of it" +
                        (f"; also stalled in {', '.join(sorted(others))}" if others else " (inside its commit)"))
    return changed


def find_program(build, rel):
    """A program of the build: at `rel`, or wherever the build put a file of its name."""
    path = os.path.join(build, rel)
    if not os.path.exists(path):
        name = os.path.basename(rel)
        found = [os.path.join(d, name) for d, _, files in os.walk(build) if name in files]
        path = found[0] if found else path
    return path


def multicast_sender_argv(feeds, port=MULTICAST_PORT):
    """soak_multicast.py in a network namespace of its own (unshare execs it, so the sender's pid
    names the namespace: /proc/PID/ns/net), sending each feed to its group on one port."""
    return ["unshare", "--net", "--", sys.executable, os.path.join(HERE, "soak_multicast.py"), "--port", str(port),
            *[",".join(f[:3]) for f in feeds]]


def live_driver_argv(program, namespace_pid, feed, stream, port=MULTICAST_PORT):
    """A live driver in the sender's network namespace (nsenter execs it: the process started is
    the driver itself), joined to its sensor's group on the shared port."""
    group, _, _, _, calibration = feed
    return ["nsenter", f"--net=/proc/{namespace_pid}/ns/net", "--", program, "--port", str(port), "--multicast",
            group, "--stream", stream, "--calibration", calibration, "--checksum", "--summary", "--quiet"]


def multicast_findings(incarnations):
    """What the live drivers on one port said when they ended: each incarnation is (process, its
    exit code, its --summary as {key: value} or None). One that exited (SIGTERM, or the end of the
    run) must have printed its summary, with no datagram of another sender, none malformed and
    none of another model: each driver joined its own group and must hear only its sensor. One
    killed by a signal (SIGKILL, or SIGTERM before its handler) says nothing. Returns one
    sentence per problem."""
    problems = []
    for process, code, summary in incarnations:
        if code is not None and code < 0:
            continue
        if summary is None:
            problems.append(f"{process} printed no summary when it was stopped")
            continue
        heard = {k: summary.get(k) for k in HEARD_ANOTHER if summary.get(k, "0") != "0"}
        if heard:
            problems.append(f"{process} heard another sensor: " + ", ".join(f"{k}={v}" for k, v in heard.items()))
    return problems


def theil_sen(points):
    """The median of the slopes between every two points (robust to a few steps and outliers)."""
    if len(points) > 240:  # enough for the median; keeps an hour's samples cheap
        step = len(points) / 240
        points = [points[int(i * step)] for i in range(240)]
    slopes = sorted((b[1] - a[1]) / (b[0] - a[0]) for i, a in enumerate(points) for b in points[i + 1:]
                    if b[0] > a[0])
    return slopes[len(slopes) // 2] if slopes else 0.0


def memory_slope(points):
    """The slope of private memory (KiB/s) and the noise it must rise above over the window: at
    least MEMORY_NOISE_KIB, or twice the interquartile range of the samples around the slope (a
    process whose memory swings by tens of MB as it churns frames, like sim_foxglove's, needs a
    run long enough for a leak to outgrow its swings)."""
    slope = theil_sen(points)
    if len(points) < 4:
        return slope, MEMORY_NOISE_KIB
    residuals = sorted(kib - slope * t for t, kib in points)
    quarter = len(residuals) // 4
    return slope, max(MEMORY_NOISE_KIB, 2 * (residuals[-1 - quarter] - residuals[quarter]))


class Soak:
    def __init__(self, args):
        self.args = args
        self.rng = random.Random(args.seed)
        self.bin = lambda rel: os.path.join(args.build, rel)
        self.workdir = tempfile.mkdtemp(prefix="sim_soak_")
        self.spawner = Spawner()
        tag = f"{os.getpid()}"
        self.cameras = [f"/soak{tag}_cam{i}" for i in range(7)]
        self.replayed_lidars = [f"/soak{tag}_lidar{i}" for i in range(2)]
        # Live drivers fed by multicast in a private network namespace (root, like the DDS bridge).
        self.live_lidars = [] if args.lean else [f"/soak{tag}_lidar{i}" for i in range(2, 2 + len(MULTICAST_FEEDS))]
        self.lidars = self.replayed_lidars + self.live_lidars
        self.multicast_pid = None
        self.programs = {}
        self.streams = self.cameras + self.lidars
        self.period = {s: CAMERA_PERIOD_MS for s in self.cameras}
        self.period.update({s: LIDAR_PERIOD_MS for s in self.lidars})
        self.children = {}   # name -> Child (the current incarnation)
        self.history = {}    # name -> [Child] (every incarnation, for the totals)
        self.violations = []
        self.lock = threading.Lock()
        self.failures = []   # crashes and hangs: (process, what)
        self.chaos = {"SIGKILL": 0, "SIGTERM": 0, "layout_replaced": 0, "sim_rm_dead": 0,
                      "sim_rm_dead_removed": 0, "record_segments": 0}
        self.resources = {}
        self.memory = {}     # process -> [(t, rss_anon_kib)] between the two resource samples
        self.publish_gaps = []  # the soak writers' own publish gaps (their "publish_gap" lines)
        self.recordings = {"played": 0, "broken": []}
        self.faults = set(args.fault or [])
        self.env = dict(os.environ)
        if self.faults:  # the test mode: the soak's own processes break what is asked
            self.env.update(SIM_SOAK_TEST_MODE="1", SIM_SOAK_FAULT=self.fault_spec())

    # ---- processes ---------------------------------------------------------------------------
    def fault_spec(self):
        """SIM_SOAK_FAULT for the soak's processes: which stream each fault hits."""
        cam, lid = self.cameras, self.lidars
        spec = {"lost_wakeups": f"lost_wakeups={lid[0]}+{cam[1]}",  # a LiDAR and a replayed camera
                "half_frames": f"half_frames={cam[4]}",
                "leak": "leak=256",                                     # KiB a second, read_block
                "stale_region": f"stale_region={cam[5]}"}
        return ",".join(spec[f] for f in sorted(self.faults) if f in spec)

    def start(self, name, argv, long_lived=False, env=None):
        child = Child(self, name, argv, long_lived, env or self.env)
        self.children[name] = child
        self.history.setdefault(name, []).append(child)
        return child

    def violation(self, process, record):
        with self.lock:
            self.violations.append({"process": process, **record})
        print(f"soak: VIOLATION in {process}: {json.dumps(record)}", flush=True)

    def fail(self, process, what):
        self.failures.append({"process": process, "what": what})
        print(f"soak: FAILURE of {process}: {what}", flush=True)

    def writer_argv(self, stream, layout="normal"):
        i = self.streams.index(stream)
        if layout == "other":  # a writer of another layout under the same name
            return [self.bin("tests/soak/sim_soak_agent"), "writer", "--stream", stream, "--hz", "30",
                    "--points", "50000"]
        if stream in self.live_lidars:
            return self.live_lidar_argv(stream)
        if stream in self.lidars:
            capture, calibration = [("pandar64_dual.pcap", "pandar64.calibration.csv"),
                                    ("pandarxt32_dual.pcap", "pandarxt32.calibration.csv")][i - 7]
            return [self.bin("replay/pcap/sim_replay_pcap"), os.path.join(HESAI, capture), "--stream", stream,
                    "--calibration", os.path.join(HESAI, calibration), "--loop", "--restamp", "--checksum",
                    "--quiet"]
        if i < self.args.video_cameras:
            return [self.bin("replay/video/sim_replay_video"), self.pictures, "--stream", stream, "--fps", "30",
                    "--loop", "--checksum", "--quiet"]
        tear = ["--tear-every", "97"] if "torn" in self.faults and stream == self.cameras[3] else []
        return [self.bin("tests/soak/sim_soak_agent"), "writer", "--stream", stream, "--hz", "30",
                "--image", self.args.image, *tear]

    def live_lidar_argv(self, stream):
        feed = MULTICAST_FEEDS[self.live_lidars.index(stream)]
        if feed[3] not in self.programs:
            self.programs[feed[3]] = find_program(self.args.build, feed[3])
        return live_driver_argv(self.programs[feed[3]], self.multicast_pid, feed, stream)

    def start_multicast(self):
        """The two sensors' sender, holding the network namespace the live drivers join."""
        sender = self.start("multicast", multicast_sender_argv(MULTICAST_FEEDS))
        deadline = time.monotonic() + 30
        while not sender.other and sender.alive() and time.monotonic() < deadline:
            time.sleep(0.05)
        ready = next((r for r in sender.other if r.get("kind") == "ready"), None)
        if not ready:
            self.fail("multicast", f"did not make its network: {sender.stderr_tail()}")
        self.multicast_pid = sender.pid  # unshare execs the sender: its namespace is /proc/PID/ns/net

    def arg(self, stream):
        return f"{stream}:{self.period[stream]:.3f}"

    def reader_argvs(self):
        agent = self.bin("tests/soak/sim_soak_agent")
        every = [self.arg(s) for s in self.streams]
        cams, lids = self.cameras, self.lidars
        python = [sys.executable, os.path.join(HERE, "soak_py_reader.py")]
        return {
            # Long-lived: their resources are measured at the start and the end.
            "read_block": ([agent, "read", "--mode", "block", *every], True),
            "read_borrow": ([agent, "read", "--mode", "borrow", *every], True),
            "read_waitset": ([agent, "waitset", *every], True),
            # The chaos loop kills and restarts these.
            "read_adaptive": ([agent, "read", "--mode", "adaptive", self.arg(cams[0]), self.arg(cams[4]),
                               self.arg(lids[0])], False),
            "read_c_camera": ([self.bin("tests/soak/sim_soak_c_reader"), cams[1]], False),
            "read_c_lidar": ([self.bin("tests/soak/sim_soak_c_reader"), lids[1]], False),
            "read_python_camera": (python + [cams[5]], False),
            "read_python_lidar": (python + [lids[0]], False),
        }

    def start_everything(self):
        os.makedirs(self.pictures, exist_ok=True)
        width, height = self.args.image.split("x")
        subprocess.run([self.bin("tests/soak/sim_soak_agent"), "make-pictures", self.pictures, "--frames", "4",
                        "--width", width, "--height", height], check=True)
        if self.live_lidars:
            self.start_multicast()
        for s in self.streams:
            self.start("writer" + s, self.writer_argv(s))
        for name, (argv, long_lived) in self.reader_argvs().items():
            self.start(name, argv, long_lived, self.python_env if "python" in name else None)
        if not self.args.lean:
            self.start_foxglove()
            self.start_dds()
        self.start_record()

    def start_foxglove(self):
        # The nine streams it always had: the live LiDARs' frames are read by the C++ readers (the
        # checks), and converting two more LiDARs at 5 Hz would cost the 2-core machine more.
        fox = self.start("sim_foxglove", [self.bin("viewer/foxglove/sim_foxglove"), "--port", "0", "--json",
                                          "--max-rate", "5", *self.cameras, *self.replayed_lidars], True)
        deadline = time.monotonic() + 30
        while not fox.other and fox.alive() and time.monotonic() < deadline:
            time.sleep(0.05)
        port = fox.other[0].get("port") if fox.other else None  # {"event":"listening",…,"port":N}
        if not port:
            self.fail("sim_foxglove", f"did not say where it listens: {fox.stderr_tail()}")
            return
        self.start("foxglove_client", ["node", os.path.join(HERE, "soak_foxglove_client.mjs"), str(port),
                                       self.cameras[2], self.lidars[1]], True)

    def start_dds(self):
        dds = self.bin("tests/soak/sim_soak_dds")
        if not os.path.exists(dds):
            self.fail("sim_soak_dds", "was not built (Cyclone DDS missing?)")
            return
        bridge = [self.bin("bridge/dds/sim_dds_bridge"), "--quiet"]
        for s in self.replayed_lidars:
            bridge += ["--publish", s]
        self.start("dds", [dds, *self.replayed_lidars, "--", *bridge], True)

    def start_record(self):
        out = os.path.join(self.workdir, "segment.mcap")
        # One LiDAR, lz4: recording both at 40 MB/s with zstd would take a core of the CI machine.
        self.start("sim_record", [self.bin("tools/sim_record/sim_record"), "-o", out, "--duration", "10",
                                  "--compression", "lz4", "--wait-for-streams", "--quiet", "--json",
                                  self.lidars[1]])

    # ---- resources of the long-lived processes -----------------------------------------------
    def long_lived_pids(self):
        pids = {n: c.pid for n, c in self.children.items() if c.long_lived and c.alive()}
        dds = self.children.get("dds")
        if dds and dds.stats and dds.stats.get("bridge_pid"):
            pids["sim_dds_bridge"] = dds.stats["bridge_pid"]
        return pids

    @staticmethod
    def sample(pid):
        try:
            status = open(f"/proc/{pid}/status").read()
            fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
            kib = lambda k: int(fields.get(k, "0 kB").split()[0])
            shm = set()
            for line in open(f"/proc/{pid}/maps"):
                if "/dev/shm/" in line:
                    shm.add(line.split(None, 5)[-1].strip())
            return {"rss_kib": kib("VmRSS"), "rss_anon_kib": kib("RssAnon"), "threads": int(fields["Threads"]),
                    "fds": len(os.listdir(f"/proc/{pid}/fd")), "shm_regions": len(shm)}
        except (OSError, KeyError, ValueError):
            return None

    def sample_all(self, when):
        for name, pid in self.long_lived_pids().items():
            s = self.sample(pid)
            if s:
                self.resources.setdefault(name, {})[when] = s
        self.resources.setdefault("/dev/shm", {})[when] = {"shm_regions": len(self.our_regions()),
                                                           "unexpected": sorted(self.unexpected_regions())}

    def our_regions(self):
        """Every region under the soak's names (/dev/shm/sim.soak<pid>_*), expected or not."""
        prefix = "sim." + self.streams[0][1:].rsplit("_", 1)[0] + "_"
        try:
            return {"/" + f[4:] for f in os.listdir("/dev/shm") if f.startswith(prefix)}
        except OSError:
            return set()

    def unexpected_regions(self):
        """The regions under the soak's names that are none of its streams, and the streams
        whose region is missing (both samples are taken with every writer running)."""
        found = self.our_regions()
        return (found - set(self.streams)) | {f"{s} (missing)" for s in set(self.streams) - found}

    def sample_memory(self):
        """Private memory of every long-lived process every MEMORY_EVERY_S, between the samples."""
        while self.sampling_memory:
            t = time.monotonic()
            for name, pid in self.long_lived_pids().items():
                s = self.sample(pid)
                if s:
                    self.memory.setdefault(name, []).append((t, s["rss_anon_kib"]))
            time.sleep(MEMORY_EVERY_S)

    # ---- the chaos loop ----------------------------------------------------------------------
    def check_stopped(self, child, sig, code):
        """A SIGTERM must end a program with exit 0 in time; a SIGKILL ends it by that signal."""
        if code is None:
            self.fail(child.name, f"still running {STOP_GRACE_S} s after {sig.name}")
        elif sig == signal.SIGTERM and code == -signal.SIGTERM and not child.handled:
            pass  # signalled before it installed its handler (still starting): it stopped at once
        elif sig == signal.SIGTERM and code != 0:
            self.fail(child.name, f"exit {code} after SIGTERM: {child.stderr_tail()}")
        elif sig == signal.SIGKILL and code not in (-signal.SIGKILL, 0):
            self.fail(child.name, f"ended with {code} before the SIGKILL: {child.stderr_tail()}")

    def restart(self, name, argv, sig, pause, long_lived=False, env=None):
        child = self.children[name]
        self.check_stopped(child, sig, child.stop(sig))
        self.chaos[sig.name] += 1
        time.sleep(pause)
        if self.running:
            self.start(name, argv, long_lived, env)

    def kill_writer(self, stream):
        sig = self.rng.choice([signal.SIGKILL, signal.SIGTERM])
        child = self.children["writer" + stream]
        self.check_stopped(child, sig, child.stop(sig))
        self.chaos[sig.name] += 1
        time.sleep(self.rng.uniform(0.2, 3.0))
        if self.rng.random() < 0.5:  # the stream is dead now: remove it, a new region will be made
            rm = subprocess.run([self.bin("tools/sim_rm"), "--dead", stream], capture_output=True, text=True)
            self.chaos["sim_rm_dead"] += 1
            if rm.returncode != 0 and "no stream named" not in rm.stderr:  # (killed before it made one)
                self.fail("sim_rm", f"--dead {stream}: exit {rm.returncode}: {rm.stderr.strip()}")
            elif "removed" in rm.stdout:
                self.chaos["sim_rm_dead_removed"] += 1
        self.start("writer" + stream, self.writer_argv(stream))

    def replace_layout(self, stream):
        """A writer of another layout takes the name over, then the stream's own writer again."""
        for layout in ("other", "normal"):
            child = self.children["writer" + stream]
            self.check_stopped(child, signal.SIGTERM, child.stop(signal.SIGTERM))
            self.start("writer" + stream, self.writer_argv(stream, layout))
            self.chaos["layout_replaced"] += 1
            time.sleep(self.rng.uniform(2.0, 5.0) if layout == "other" else 0)

    def kill_reader(self, name):
        argv, long_lived = self.reader_argvs()[name]
        sig = self.rng.choice([signal.SIGKILL, signal.SIGTERM])
        self.restart(name, argv, sig, self.rng.uniform(0.2, 2.0), long_lived,
                     self.python_env if "python" in name else None)

    def guarded(self, action, target):
        """A chaos action; one that cannot start a program is a failure, and the program is
        started again (so one failure does not stop a stream for the rest of the run)."""
        try:
            action(target)
        except Exception as e:  # noqa: BLE001 — reported, then recovered
            self.fail(target, f"{action.__name__}: {e}")
            name = ("writer" + target) if target in self.streams else target
            argv = self.writer_argv(target) if target in self.streams else self.reader_argvs()[target][0]
            time.sleep(1)
            self.start(name, argv, False, self.python_env if "python" in target else None)

    def chaos_loop(self, until):
        busy = set()
        threads = []
        victims = [n for n, (_, long_lived) in self.reader_argvs().items() if not long_lived]
        while time.monotonic() < until:
            time.sleep(self.rng.uniform(0.5, 2.0))
            threads = [t for t in threads if t.is_alive()]
            busy = {t.name for t in threads}
            roll = self.rng.random()
            if roll < 0.45:
                target, action = self.rng.choice(self.streams), self.kill_writer
            elif roll < 0.55:
                target, action = self.rng.choice(self.cameras), self.replace_layout
            else:
                target, action = self.rng.choice(victims), self.kill_reader
            if target in busy:
                continue
            t = threading.Thread(target=self.guarded, args=(action, target), name=target, daemon=True)
            t.start()
            threads.append(t)
        for t in threads:
            t.join()

    def play_back(self, child, ended_by):
        """Reads a finished segment back with sim_play (into a stream of another name) before it is
        deleted: a segment that sim_record ended cleanly (--duration or SIGTERM) must play every
        frame it says it wrote; one killed by SIGKILL may be cut short and is only played."""
        path = os.path.join(self.workdir, "segment.mcap")
        said = next((r for r in child.other if "streams" in r), None)
        if not os.path.exists(path):
            if ended_by != "SIGKILL":
                self.recordings["broken"].append(f"{ended_by}: no file")
            return
        if "broken_recording" in self.faults:  # the fault: a recorder that wrote half a file
            with open(path, "r+b") as f:
                f.truncate(os.path.getsize(path) // 2)
        tag = self.streams[0][1:].rsplit("_", 1)[0]
        play = subprocess.run([self.bin("tools/sim_play/sim_play"), path, "--max-rate", "--remap",
                               f"{self.lidars[1]}=/{tag}play_lidar1"], capture_output=True, text=True)
        out = play.stdout + play.stderr
        counts = re.findall(r"\bframes (\d+)", out)  # its summary line: "frames N  passes 1  …"
        played = int(counts[-1]) if counts else -1
        self.recordings["played"] += 1
        if ended_by == "SIGKILL" or child.proc.returncode != 0:  # (a SIGTERM before its handler: killed)
            return
        wrote = sum(st.get("frames", 0) for st in said["streams"]) if said else None
        if play.returncode != 0 or wrote is None or played != wrote or (ended_by == "duration" and wrote == 0 and self.running):
            self.recordings["broken"].append(
                f"{ended_by}: sim_record said {wrote} frames, sim_play exit {play.returncode} played {played}: "
                f"{out.strip()[-200:]}")

    def record_loop(self):
        """sim_record in segments of 10 s (the files stay small), now and then stopped early; every
        segment is played back before it is deleted."""
        while self.running:
            child = self.children["sim_record"]
            ended_by = "duration"
            if self.rng.random() < 0.3:
                time.sleep(self.rng.uniform(1, 8))
                sig = self.rng.choice([signal.SIGKILL, signal.SIGTERM])
                self.check_stopped(child, sig, child.stop(sig))
                self.chaos[sig.name] += 1
                ended_by = sig.name
            else:
                try:
                    code = child.proc.wait(10 + 60)
                except subprocess.TimeoutExpired:
                    code = child.stop(signal.SIGTERM)
                    self.fail("sim_record", "did not end 60 s after its --duration")
                if code != 0:
                    self.fail("sim_record", f"exit {code} at the end of its --duration: {child.stderr_tail()}")
                self.chaos["record_segments"] += 1
                child.reader.join(5)  # its JSON line
            self.play_back(child, ended_by)
            for f in os.listdir(self.workdir):
                if f.endswith(".mcap"):
                    os.remove(os.path.join(self.workdir, f))
            if self.running:
                self.start_record()

    # ---- watching ----------------------------------------------------------------------------
    def watch(self):
        """Crashes (a process that ended without being asked) and hangs (silent readers)."""
        next_progress = self.t0 + PROGRESS_EVERY_S
        while self.running:
            time.sleep(0.5)
            if time.monotonic() >= next_progress:
                next_progress += PROGRESS_EVERY_S
                self.print_progress()
            for name, child in list(self.children.items()):
                if child.signalled is not None or child.ended_reported or name == "sim_record":
                    continue
                if not child.alive():
                    child.ended_reported = True
                    self.fail(name, f"ended by itself with {child.proc.returncode}: {child.stderr_tail()}")
                elif (child.stats is not None or name.startswith("read") or name in ("dds", "foxglove_client")) \
                        and time.monotonic() - child.last_line > SILENCE_S:
                    child.ended_reported = True
                    self.fail(name, f"printed nothing for {SILENCE_S} s (hung)")

    def print_progress(self):
        """One line a minute, so a person watching an hour-long run sees it alive and clean."""
        elapsed = time.monotonic() - self.t0
        kills = self.chaos["SIGKILL"] + self.chaos["SIGTERM"]
        frames = sum(self.progress().values())
        print(f"soak: {elapsed / 60:.0f} of {self.args.seconds / 60:.0f} min, {frames:,} frames to the "
              f"long-lived readers, {kills} kills, {self.chaos['layout_replaced']} layout replacements, "
              f"{len(self.violations)} violations, {len(self.failures)} failures", flush=True)

    def progress(self):
        """Frames each long-lived consumer has had so far, per stream."""
        seen = {}
        for name in ("read_block", "read_borrow", "read_waitset"):
            c = self.children.get(name)
            for stream, counters in ((c.stats or {}).get("streams", {}) if c else {}).items():
                seen[(name, stream)] = counters["frames"]
        for name, key, count in (("foxglove_client", "topics", "messages"), ("dds", "topics", "clouds")):
            c = self.children.get(name)
            for topic, counters in ((c.stats or {}).get(key, {}) if c else {}).items():
                seen[(name, topic)] = counters[count]
        return seen

    # ---- the run -----------------------------------------------------------------------------
    def run(self):
        seconds = self.args.seconds
        warmup = self.args.warmup or max(20.0, 0.15 * seconds)  # with chaos: caches and pools reach their size
        calm = 8.0                            # no chaos, every writer back: the start sample
        settle = max(12.0, min(30.0, 0.05 * seconds))
        self.pictures = os.path.join(self.workdir, "pictures")
        self.python_env = dict(self.env, PYTHONPATH=self.bin("python"), PYTHONDONTWRITEBYTECODE="1")
        self.running = True
        self.t0 = time.monotonic()
        self.start_everything()
        watcher = threading.Thread(target=self.watch, daemon=True)
        watcher.start()
        recorder = threading.Thread(target=self.record_loop, daemon=True)
        recorder.start()
        time.sleep(5)
        self.chaos_loop(self.t0 + warmup)
        time.sleep(calm)
        self.sample_all("start")
        self.sampling_memory = True
        memory = threading.Thread(target=self.sample_memory, daemon=True)
        memory.start()
        print(f"soak: warmed up; chaos until {seconds - settle:.0f} s", flush=True)
        self.chaos_loop(self.t0 + seconds - settle)
        # Settled: every writer is back. Every long-lived consumer must still get frames.
        time.sleep(max(2.0, settle - 7))
        before = self.progress()
        time.sleep(5)
        after = self.progress()
        for key, count in before.items():
            if after.get(key, count) <= count:
                self.fail(key[0], f"got no frame of {key[1]} in the last 5 s although its writer runs (hung)")
        for name in ("read_block", "read_borrow", "read_waitset"):
            for stream in self.streams:
                if (name, stream) not in after:
                    self.fail(name, f"never reported {stream}")
        self.sample_all("end")
        self.sampling_memory = False
        memory.join(MEMORY_EVERY_S + 5)
        self.running = False
        record = self.children["sim_record"]
        if record.alive():
            self.check_stopped(record, signal.SIGTERM, record.stop(signal.SIGTERM))
        recorder.join(STOP_GRACE_S + 5)
        self.stop_everything()
        self.elapsed = time.monotonic() - self.t0

    def stop_everything(self):
        order = sorted(self.children.values(), key=lambda c: (c.name.startswith("writer"), c.name == "sim_foxglove"))
        for child in order:  # readers first, so they report their last counters; writers last
            if child.name == "sim_record" and not child.alive():
                continue
            if not child.alive() and child.signalled is None:
                continue  # already reported as a crash
            code = child.stop(signal.SIGTERM)
            self.check_stopped(child, signal.SIGTERM, code)
        dds = self.children.get("dds")
        if dds and dds.stats and dds.stats.get("bridge_exit") not in (None, "exit 0"):
            self.fail("sim_dds_bridge", f"{dds.stats['bridge_exit']} after SIGTERM")
        # Every writer ended: only the streams' regions may remain (a writer leaves its region
        # for late readers; sim_rm --dead removes it). Anything else under the soak's names was
        # left behind by one of its programs.
        self.stale = sorted(self.our_regions() - set(self.streams))
        subprocess.run([self.bin("tools/sim_rm"), "--dead", *self.streams], capture_output=True)
        self.left_behind = len(self.our_regions() - set(self.stale)) + len(self.stale)
        subprocess.run([self.bin("tools/sim_rm"), "--force", *self.stale], capture_output=True)
        shutil.rmtree(self.workdir, ignore_errors=True)

    # ---- the report --------------------------------------------------------------------------
    def totals(self):
        """Counters of every incarnation of every reader, by kind of reader."""
        kinds = {}
        for name, incarnations in self.history.items():
            if name.startswith("writer"):
                continue
            for child in incarnations:
                stats = child.stats or {}
                per = stats.get("streams") or stats.get("topics") or {}
                k = kinds.setdefault(name, {"processes": 0})
                k["processes"] += 1
                for counters in per.values():
                    for key, value in counters.items():
                        if isinstance(value, (int, float)) and key != "worst_stall_ms":
                            k[key] = k.get(key, 0) + value
                        elif key == "worst_stall_ms":
                            k[key] = max(k.get(key, 0), value)
                if name == "foxglove_client" and stats.get("page"):
                    for key, value in stats["page"].items():
                        k["page_" + key] = k.get("page_" + key, 0) + value
        return kinds

    def resource_checks(self):
        rows = []
        for name, when in sorted(self.resources.items()):
            if "start" not in when or "end" not in when:
                if name != "/dev/shm":
                    self.fail(name, "was not running at both resource samples")
                continue
            a, b = when["start"], when["end"]
            # The Node client is the test's viewer, not part of the vehicle: its garbage-collected
            # heap and keep-alive sockets are shown, not judged.
            judged = name != "foxglove_client"
            # Private memory: an allocator keeps freed buffers of a frame's size for reuse (glibc
            # raises its mmap threshold to the largest block freed), so a process that handles
            # 6.9 MB frames may hold a few more at the end without leaking; a leak of anything per
            # frame or per chaos event would be far more over thousands of frames and events.
            if name == "/dev/shm":  # exactly the streams' regions, at both samples
                unexpected = sorted(set(a["unexpected"]) | set(b["unexpected"]))
                rows.append({"process": name, "what": "shm_regions", "start": a["shm_regions"],
                             "end": b["shm_regions"], "limit": f"the {len(self.streams)} streams' only",
                             "ok": not unexpected, "unexpected": unexpected})
                continue
            limits = {"fds": 2, "threads": 2, "shm_regions": 1}
            if "rss_anon_kib" in a:
                rows.append(self.memory_row(name, a, b, judged))
            for key, limit in limits.items():
                if key in a:
                    rows.append({"process": name, "what": key, "start": a[key], "end": b[key],
                                 "limit": f"+{limit:.0f}" if judged else "shown",
                                 "ok": b[key] - a[key] <= limit or not judged})
            if "rss_kib" in a:
                rows.append({"process": name, "what": "rss_kib (with shared memory touched)", "start": a["rss_kib"],
                             "end": b["rss_kib"], "limit": "shown", "ok": True})
        return rows

    def memory_row(self, name, a, b, judged):
        """Private memory must be flat: its slope over the judged window, not its total growth
        (an allocator that keeps a few freed frames is a step, a leak is a slope)."""
        points = self.memory.get(name, [])
        window = points[-1][0] - points[0][0] if len(points) > 1 else 0.0
        judged = judged and window >= MEMORY_JUDGED_FROM_S.get(name, 0)
        slope, noise = memory_slope(points)
        slope *= 60  # KiB a minute
        limit = max(noise / window * 60 if window > 0 else float("inf"), MEMORY_SLOPE_KIB_PER_H / 60)
        # A leak also ends above every earlier peak; memory that rises and falls (a DDS stack's
        # buffers) can have a rising median slope and still end lower than it began.
        early = [kib for _, kib in points[:max(1, len(points) // 4)]]
        rise = points[-1][1] - max(early) if points else 0
        return {"process": name, "what": "rss_anon_kib", "start": a["rss_anon_kib"], "end": b["rss_anon_kib"],
                "limit": f"slope {limit:.0f} KiB/min" if judged else "shown", "slope_kib_per_min": round(slope, 1),
                "rise_over_first_quarter_kib": rise, "samples": len(points),
                "noise_kib": round(noise), "ok": slope <= limit or rise <= noise or not judged}

    def multicast_report(self):
        """The live drivers' summaries judged (multicast_findings), and what the sender sent."""
        if not self.live_lidars:
            return {"problems": [], "detail": "not run (--lean)", "summaries": []}
        runs = [("writer" + s, c.proc.returncode, c.summary) for s in self.live_lidars
                for c in self.history.get("writer" + s, [])]
        sender = self.children.get("multicast")
        groups = (sender.stats or {}).get("groups", {}) if sender else {}
        frames = sum(int((summary or {}).get("frames", 0)) for _, _, summary in runs)
        sent = ", ".join(f"{g}: {c['sent']}" for g, c in groups.items())
        return {"problems": multicast_findings(runs), "summaries": [list(r) for r in runs],
                "detail": f"{len(runs)} driver runs, {frames} frames in their summaries; datagrams sent: {sent}"}

    def deliveries(self):
        """Frames each long-lived (or restarted C++) reader got per stream, against the frames the
        writer published while it read them (got + skipped), over all its incarnations."""
        rows = {}
        for name in ("read_block", "read_borrow", "read_waitset", "read_adaptive"):
            for child in self.history.get(name, []):
                for stream, c in ((child.stats or {}).get("streams") or {}).items():
                    r = rows.setdefault((name, stream), {"reader": name, "stream": stream, "frames": 0,
                                                         "skipped": 0, "lost": 0})
                    for key in ("frames", "skipped", "lost"):
                        r[key] += c.get(key, 0)
        for r in rows.values():
            published = r["frames"] + r["lost"]
            r["share"] = round(r["frames"] / published, 3) if published else 1.0
            r["ok"] = published < 30 or r["share"] >= DELIVERY_FLOOR
        return sorted(rows.values(), key=lambda r: r["share"])

    def report(self):
        writer_stalls = classify_stalls(self.violations, self.publish_gaps)
        kinds = self.totals()
        count = lambda what: sum(1 for v in self.violations if v.get("what") == what)
        deliveries = self.deliveries()
        short = [r for r in deliveries if not r["ok"]]
        worst = deliveries[0] if deliveries else None
        timed = sum(k.get("timed", 0) for k in kinds.values())
        untimed = sum(k.get("untimed", 0) for k in kinds.values())
        worst_stall = max([k.get("worst_stall_ms", 0) for k in kinds.values()] or [0])
        frames = sum(k.get("frames", 0) for k in kinds.values())
        resources = self.resource_checks()
        other = [v for v in self.violations
                 if v.get("what") not in ("torn", "out_of_order", "missed", "backwards", "writer_stall")]
        multicast = self.multicast_report()
        checks = [
            ("torn frames (pattern, structure or checksum)", count("torn"), f"{frames} frames read"),
            ("out-of-order frames (SIM sequence, DDS and Foxglove stamps)",
             count("out_of_order") + count("backwards") + sum(k.get("out_of_order", 0) for n, k in kinds.items() if n == "dds"),
             ""),
            ("blocked reader missed the newest frame > 2 periods", count("missed"),
             f"{timed} waits timed, {untimed} not timeable, worst net stall {worst_stall:.1f} ms"),
            (f"long-lived readers given under {DELIVERY_FLOOR:.0%} of the frames published (slept through)", len(short),
             f"worst {worst['share']:.1%} ({worst['reader']} {worst['stream']})" if worst else ""),
            ("crashes or hangs", len(self.failures), ""),
            ("other violations (DDS malformed, Foxglove undecodable, page errors)",
             len(other) + sum(k.get("malformed", 0) for k in kinds.values()), ""),
            ("resources of long-lived processes outside tolerance", sum(1 for r in resources if not r["ok"]),
             f"{len({r['process'] for r in resources})} processes"),
            ("our /dev/shm regions left behind", self.left_behind, ", ".join(self.stale)),
            ("recordings that do not play back whole (sim_play)", len(self.recordings["broken"]),
             f"{self.recordings['played']} segments played back"),
            ("live LiDARs on one port (two multicast groups) that heard the other sensor or did not say",
             len(multicast["problems"]), multicast["detail"]),
        ]
        ok = all(value == 0 for _, value, _ in checks)
        # Shown, never failed: the writer (or the whole machine) paused, not the transport.
        checks.append(("writer or machine stalls (the writer paused inside its commit, or with every reader; shown)",
                       writer_stalls, f"{len(self.publish_gaps)} publish gaps of the soak writers"))
        lines = [f"SIM soak: {self.elapsed:.0f} s, seed {self.args.seed}, {len(self.streams)} streams",
                 "", "| check | result | detail |", "|---|---|---|"]
        lines += [f"| {what} | {value} | {detail} |" for what, value, detail in checks]
        lines += ["", "| reader | processes | frames | skipped (slept through) | torn | out of order | "
                      "missed (writer stalls included) | overwritten (borrow) |", "|---|---|---|---|---|---|---|---|"]
        for name, k in sorted(kinds.items()):
            if name.startswith("read"):
                lines.append(f"| {name} | {k['processes']} | {k.get('frames', 0)} | {k.get('skipped', '-')} ({k.get('lost', '-')}) | {k.get('torn', 0)} | "
                             f"{k.get('out_of_order', 0)} | {k.get('missed', '-')} | {k.get('overwritten', '-')} |")
        fox, dds = kinds.get("foxglove_client", {}), kinds.get("dds", {})
        lines += ["", f"Foxglove client: {fox.get('messages', 0)} messages, {fox.get('page_fetches', 0)} page fetches "
                      f"({fox.get('page_failures', 0)} failed, {fox.get('page_image_unavailable', 0)} images between writers); "
                      f"DDS (Cyclone, private network): {dds.get('clouds', 0)} clouds; sim_record: "
                      f"{self.chaos['record_segments']} segments ended by --duration",
                  "Chaos: " + ", ".join(f"{k} {v}" for k, v in self.chaos.items()),
                  "", "| process | resource | start | end | allowed growth | ok |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['process']} | {r['what']} | {r['start']} | {r['end']} | {r['limit']} | {'yes' if r['ok'] else 'NO'} |"
                  for r in resources]
        lines += ["", "PASS" if ok else "FAIL"]
        for f in self.failures:
            lines.append(f"  failure: {f['process']}: {f['what']}")
        for r in short:
            lines.append(f"  delivery: {r['reader']} got {r['frames']} frames of {r['stream']} and slept through "
                         f"{r['lost']} ({r['share']:.1%}; {r['skipped']} skipped in all)")
        for r in resources:
            if not r["ok"]:
                lines.append(f"  resource: {json.dumps(r)}")
        for b in self.recordings["broken"]:
            lines.append(f"  recording: {b}")
        for m in multicast["problems"]:
            lines.append(f"  multicast: {m}")
        for v in self.violations[:20]:
            lines.append(f"  violation: {json.dumps(v)}")
        print("\n".join(lines), flush=True)
        result = {"seconds": round(self.elapsed, 1), "seed": self.args.seed, "pass": ok,
                  "checks": [{"check": w, "value": v, "detail": d} for w, v, d in checks],
                  "readers": kinds, "chaos": self.chaos, "resources": resources,
                  "failures": self.failures, "violations": self.violations, "deliveries": deliveries,
                  "publish_gaps": self.publish_gaps, "recordings": self.recordings, "multicast": multicast,
                  "faults": sorted(self.faults), "judged": [c[0] for c in checks[:-1]],
                  # private memory over the run, for people judging a slope: [seconds, KiB], ≤ 120 a process
                  "memory": {name: [[round(t - self.t0, 1), kib] for t, kib in points[::max(1, len(points) // 120)]]
                             for name, points in self.memory.items()}}
        if self.args.json:
            with open(self.args.json, "w") as f:
                json.dump(result, f, indent=1)
        return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", required=True, help="the build folder (build/release)")
    parser.add_argument("--seconds", type=float, default=120, help="how long the whole soak runs")
    parser.add_argument("--seed", type=int, default=int(time.time()), help="the chaos loop's random seed")
    parser.add_argument("--json", help="also write the result as JSON to this file")
    parser.add_argument("--video-cameras", type=int, default=2,
                        help="cameras written by sim_replay_video (the rest by the soak writer)")
    parser.add_argument("--image", default="1920x1200", help="the cameras' size, WxH")
    parser.add_argument("--lean", action="store_true",
                        help="without sim_foxglove and the DDS bridge (no root needed; the fault test)")
    parser.add_argument("--warmup", type=float, help="seconds of warm-up before the first resource sample "
                        "(default: 15 %% of the run, at least 20)")
    parser.add_argument("--fault", type=lambda t: FAULTS if t == "all" else t.split(","),
                        help="break something on purpose (the test of the soak itself): a comma list of "
                             + ", ".join(FAULTS) + ", or all; the soak must then fail")
    args = parser.parse_args()
    if args.seconds < 40:
        parser.error("--seconds must be at least 40 (warm-up, chaos and the settled end)")
    for f in args.fault or []:
        if f not in FAULTS:
            parser.error(f"--fault {f} is not one of {', '.join(FAULTS)}")
    soak = Soak(args)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: sys.exit(130))
    try:
        soak.run()
        ok = soak.report()
    finally:
        soak.running = False
        for child in list(soak.children.values()):  # (a chaos thread may still add one)
            if child.alive():
                child.proc.kill()
        subprocess.run([soak.bin("tools/sim_rm"), "--force", *soak.streams, *soak.our_regions()], capture_output=True)
        shutil.rmtree(soak.workdir, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
