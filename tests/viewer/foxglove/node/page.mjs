// SPDX-License-Identifier: Apache-2.0
// The built-in page in a real browser: headless Chromium (Debian's /usr/bin/chromium, driven by
// puppeteer-core) opens http://127.0.0.1:PORT/ while the Pandar64 recording, a camera replay and
// a calibrated camera with a mounted LiDAR (sensor_writer) run. It asserts the page lists the
// streams with a live writer, shows a camera image and a LiDAR top-down view that are not blank,
// draws the LiDAR's points into the calibrated camera's image where the mountings put them,
// shows a colour legend with the scale's numbers, marks a dead writer's picture, replaces a
// view whose stream changed kind, says so when there are no streams, and greys everything out
// with a banner when the server is gone. Screenshots are kept as artifacts (the projection one
// is the picture in docs/foxglove.md).
import assert from "node:assert/strict";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { spawnSync } from "node:child_process";
import puppeteer from "puppeteer-core";

import * as h from "./harness.mjs";

h.deadline(200, "the page test");
const chromium = process.env.SIM_CHROMIUM || "/usr/bin/chromium";
const artifacts = process.env.SIM_TEST_ARTIFACTS || os.tmpdir();
fs.mkdirSync(artifacts, { recursive: true });

const lidar = h.uniqueStream("page_lidar");
const camera = h.uniqueStream("page_camera");
const calibrated = h.uniqueStream("page_calibrated");
const mountedLidar = h.uniqueStream("page_mounted_lidar");
h.startLidar(lidar);
const video = h.startVideo(camera, h.writeImageFolder());
await h.startSensorWriter(calibrated, mountedLidar);
const server = await h.startFoxglove([], [lidar, camera, calibrated, mountedLidar]);

// Waits (30 s) for `fn(arg)` to hold in `page`; when it does not, fails with what the page
// showed and what the server listed. This wait ("writer gone") timed out now and then in loaded
// ctest runs, never alone: the details say which side was late.
async function waitOrExplain(page, fn, arg, what) {
  try {
    await page.waitForFunction(fn, { timeout: 30_000 }, arg);
  } catch (e) {
    const views = await page.$$eval(".view", (all) => all.map((v) =>
      `${v.dataset.stream} [${v.dataset.key}] "${v.querySelector(".stale-mark")?.textContent ?? ""}"`))
      .catch((f) => [String(f)]);
    const banner = await page.$eval("#banner", (b) => `${b.className} ${b.textContent}`).catch((f) => String(f));
    let listed;
    try {
      const response = await fetch(`http://127.0.0.1:${server.port}/api/streams`, { signal: AbortSignal.timeout(10_000) });
      listed = await response.text();
    } catch (f) {
      listed = String(f);
    }
    throw new Error(`${what}: ${e.message}\nviews: ${views.join("; ")}\nbanner: ${banner}\n/api/streams: ${listed}`);
  }
}

const profile = fs.mkdtempSync(path.join(os.tmpdir(), "sim_foxglove_chromium_"));
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  userDataDir: profile,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage"],
});
process.on("exit", () => {
  try { browser.process()?.kill("SIGKILL"); } catch { /* already gone */ }
  fs.rmSync(profile, { recursive: true, force: true });
});

// Measures the picture of a stream's view in the same step that finds it loaded (the page swaps
// each <img>'s source as frames come). `region` counts pixels unlike the grey background
// (coloured points) inside a rectangle and outside it.
async function measure(page, name, { urlPattern = "", region = null } = {}) {
  const measured = await page.waitForFunction((n, pattern, r) => {
    const img = document.querySelector(`.view[data-stream="${n}"] img`);
    if (!img || !img.complete || img.naturalWidth === 0) return null;
    if (pattern && !new RegExp(pattern).test(img.dataset.url || "")) return null;
    const canvas = document.createElement("canvas");
    canvas.width = img.naturalWidth;
    canvas.height = img.naturalHeight;
    const ctx = canvas.getContext("2d");
    ctx.drawImage(img, 0, 0);
    const { data } = ctx.getImageData(0, 0, canvas.width, canvas.height);
    const colours = new Set();
    let lit = 0, inside = 0, outside = 0;
    for (let i = 0; i < data.length; i += 4) {
      colours.add((data[i] >> 4) * 256 + (data[i + 1] >> 4) * 16 + (data[i + 2] >> 4));
      if (data[i] + data[i + 1] + data[i + 2] > 150) ++lit;
      if (r) {
        const x = (i / 4) % canvas.width, y = Math.floor(i / 4 / canvas.width);
        const marked = Math.max(Math.abs(data[i] - 50), Math.abs(data[i + 1] - 50), Math.abs(data[i + 2] - 50)) > 40;
        if (marked && x >= r.left && x <= r.right && y >= r.top && y <= r.bottom) ++inside;
        else if (marked) ++outside;
      }
    }
    return { width: canvas.width, height: canvas.height, colours: colours.size, lit, inside, outside };
  }, { timeout: 60_000, polling: 100 }, name, urlPattern, region);
  return measured.jsonValue();
}

const rowText = (page, name) => page.$$eval("#streams tbody tr",
  (trs, n) => trs.find((r) => r.dataset.stream === n)?.textContent || "", name);

try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 1000 });
  await page.goto(`http://127.0.0.1:${server.port}/`, { waitUntil: "domcontentloaded" });

  // Every stream in the table, with a live writer and a rate.
  for (const name of [lidar, camera, calibrated, mountedLidar]) {
    await page.waitForFunction((n) => {
      const row = [...document.querySelectorAll("#streams tbody tr")].find((r) => r.dataset.stream === n);
      return row && /alive/.test(row.textContent) && / Hz/.test(row.textContent);
    }, { timeout: 60_000 }, name);
  }
  assert.ok((await rowText(page, lidar)).includes("points lidar_point"));
  assert.ok((await rowText(page, camera)).includes("bgr8"));
  const calibratedRow = await rowText(page, calibrated);
  assert.ok(calibratedRow.includes(`${h.scene.cameraFrame} in base_link`), calibratedRow);
  assert.ok(calibratedRow.includes("fx=200"), calibratedRow);
  assert.ok(calibratedRow.includes(`${calibrated}/camera_info`), calibratedRow);

  // Each stream's clock: the server's summary line, in the colour of its verdict.
  const clockCell = (n) => page.$$eval("#streams tbody tr", (trs, name) => {
    const cell = trs.find((r) => r.dataset.stream === name)?.querySelector("td.clock");
    return cell ? { text: cell.textContent, cls: cell.className, title: cell.title } : null;
  }, n);
  const served = await page.evaluate(() => fetch("/api/streams").then((r) => r.json()));
  const clockOf = (n) => served.find((s) => s.name === n)?.clock;
  assert.equal(clockOf(calibrated)?.verdict, "warn", JSON.stringify(served));
  assert.equal(clockOf(calibrated)?.problem, h.scene.cameraClockProblem);
  const cameraClock = await clockCell(calibrated);
  assert.equal(cameraClock?.text, clockOf(calibrated).summary);
  assert.equal(cameraClock.cls, "clock warn");
  assert.equal(cameraClock.title, h.scene.cameraClockProblem);
  const lidarClock = await clockCell(mountedLidar);
  assert.equal(lidarClock?.text, clockOf(mountedLidar).summary);
  assert.equal(lidarClock.cls, "clock ok");

  const cameraPicture = await measure(page, camera);
  assert.equal(cameraPicture.width, h.image.width);
  assert.equal(cameraPicture.height, h.image.height);
  assert.ok(cameraPicture.colours > 50, `camera image has only ${cameraPicture.colours} colours`);
  // A picture under 320 pixels wide is scaled up to a readable size (review L6).
  const shownWidth = await page.$eval(`.view[data-stream="${camera}"] img`, (img) => img.getBoundingClientRect().width);
  assert.ok(shownWidth >= 320, `a 160-pixel picture is shown ${shownWidth} pixels wide`);
  // A camera picture has no colour scale: its legend is not displayed (issue 32: the legend's
  // CSS display rule overrode the hidden attribute, so every camera showed an empty scale).
  const cameraLegend = await page.$eval(`.view[data-stream="${camera}"] .legend`,
                                        (l) => ({ hidden: l.hidden, display: getComputedStyle(l).display }));
  assert.deepEqual(cameraLegend, { hidden: true, display: "none" }, "an empty colour scale under the camera view");
  const lidarPicture = await measure(page, lidar);
  assert.ok(lidarPicture.colours > 20, `top-down view has only ${lidarPicture.colours} colours`);
  assert.ok(lidarPicture.lit > 2000, `top-down view shows only ${lidarPicture.lit} bright pixels`);

  // Intensity colouring is a different picture of the same frame; the caption names the scale.
  await page.select(`.view[data-stream="${lidar}"] select`, "intensity");
  await page.waitForFunction((n) => {
    const view = document.querySelector(`.view[data-stream="${n}"]`);
    return view.querySelector("img").complete && /color=intensity/.test(view.querySelector("img").dataset.url || "") &&
      /colour: intensity .* \(blue\) to .* \(red\)/.test(view.querySelector(".caption").textContent);
  }, { timeout: 30_000 }, lidar);
  // Beside the caption, a colour legend with the same numbers and the Turbo scale (review L6).
  const legend = await page.$eval(`.view[data-stream="${lidar}"]`, (view) => ({
    caption: view.querySelector(".caption").textContent,
    hidden: view.querySelector(".legend").hidden,
    text: view.querySelector(".legend").textContent,
    bar: view.querySelector(".legend .bar").style.background,
  }));
  assert.equal(legend.hidden, false, "no colour legend under the LiDAR view");
  const scale = /colour: intensity (\S+) \(blue\) to (\S+) \(red\)/.exec(legend.caption);
  assert.ok(scale, legend.caption);
  assert.equal(legend.text, `intensity:${scale[1]}${scale[2]}`, "the legend's numbers are not the caption's");
  assert.match(legend.bar, /linear-gradient/);

  // The calibrated camera shows its LiDAR's points by default, where calibration and mountings
  // put them: the wall ahead lands in its rectangle, the wall behind nowhere. A wrong transform
  // or intrinsics would draw them elsewhere (or not at all).
  const wall = h.scene.wall;
  const projected = await measure(page, calibrated, {
    urlPattern: "lidar=" + encodeURIComponent(mountedLidar),
    region: { left: wall.left - 3, right: wall.right + 3, top: wall.top - 3, bottom: wall.bottom + 3 },
  });
  assert.ok(projected.inside > 1500, `only ${projected.inside} projected pixels where the wall is`);
  assert.ok(projected.outside < projected.inside / 50,
            `${projected.outside} marked pixels outside the wall (${projected.inside} inside)`);
  const caption = await page.$eval(`.view[data-stream="${calibrated}"] .caption`, (c) => c.textContent);
  assert.match(caption, /^1681 of 3362 points/, caption);
  const shot = path.join(artifacts, "sim_foxglove_projection.png");
  await page.screenshot({ path: shot, fullPage: true });
  console.log(`ok: ${projected.inside} pixels of projected points on the wall, ${projected.outside} elsewhere; screenshot ${shot}`);

  // A writer that died: its picture is marked stale, not passed off as live.
  video.kill("SIGKILL");
  await waitOrExplain(page, (n) => /writer gone/.test(
    document.querySelector(`.view[data-stream="${n}"] .stale-mark`)?.textContent || ""),
    camera, "the dead writer's view was not marked 'writer gone'");
  // A stream whose name is taken by another kind gets a new view (the LiDAR becomes a camera).
  spawnSync(h.bin.rm, ["--force", lidar], { stdio: "ignore" });
  h.startVideo(lidar, h.writeImageFolder());
  await page.waitForFunction((n) => {
    const view = document.querySelector(`.view[data-stream="${n}"]`);
    return view && view.dataset.kind === "image" && view.querySelector("img").naturalWidth === 160;
  }, { timeout: 30_000 }, lidar);
  console.log("ok: a dead writer's picture is marked; a stream that changed kind got a new view");

  // The server goes away: a banner says so and the table is struck through, not left green.
  await h.stop(server.child);
  await page.waitForFunction(() => document.getElementById("banner").classList.contains("shown") &&
    document.getElementById("streams").classList.contains("stale"), { timeout: 30_000 });
  const banner = await page.$eval("#banner", (b) => b.textContent);
  assert.match(banner, /Lost contact with sim_foxglove at .*Retrying/);
  await page.screenshot({ path: path.join(artifacts, "sim_foxglove_page_server_gone.png"), fullPage: true });
  console.log("ok: the page says it lost contact with the server and greys out its data");

  // No streams at all: a sentence that says how to start one.
  const empty = await h.startFoxglove([], [h.uniqueStream("page_nothing")]);
  await page.goto(`http://127.0.0.1:${empty.port}/`, { waitUntil: "domcontentloaded" });
  await page.waitForFunction(() => !document.getElementById("empty").hidden, { timeout: 30_000 });
  assert.match(await page.$eval("#empty", (e) => e.textContent), /No SIM streams on this machine yet/);
  await h.stop(empty.child);
  console.log("ok: a page with no streams says how to start one");
} finally {
  await browser.close();
}
assert.equal(server.child.exitCode, 0, server.child.stderrText);
console.log("PASS");
process.exit(0);
