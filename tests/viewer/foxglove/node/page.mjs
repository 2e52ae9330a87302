// SPDX-License-Identifier: Apache-2.0
// The built-in page in a real browser: headless Chromium (Debian's /usr/bin/chromium, driven by
// puppeteer-core) opens http://127.0.0.1:PORT/ while the Pandar64 recording and a camera replay
// run, and the test asserts the page lists both streams with a live writer and shows a camera
// image and a LiDAR top-down view that are not blank. The screenshot is kept as an artifact.
import assert from "node:assert/strict";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import puppeteer from "puppeteer-core";

import * as h from "./harness.mjs";

h.deadline(150, "the page test");
const chromium = process.env.SIM_CHROMIUM || "/usr/bin/chromium";
const artifacts = process.env.SIM_TEST_ARTIFACTS || os.tmpdir();

const lidar = h.uniqueStream("page_lidar");
const camera = h.uniqueStream("page_camera");
h.startLidar(lidar);
h.startVideo(camera, h.writeImageFolder());
const server = await h.startFoxglove([], [lidar, camera]);

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

try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 1000 });
  await page.goto(`http://127.0.0.1:${server.port}/`, { waitUntil: "domcontentloaded" });

  // Both streams in the table, with a live writer and a rate.
  for (const name of [lidar, camera]) {
    await page.waitForFunction((n) => {
      const row = [...document.querySelectorAll("#streams tbody tr")].find((r) => r.dataset.stream === n);
      return row && /alive/.test(row.textContent) && / Hz/.test(row.textContent);
    }, { timeout: 60_000 }, name);
  }
  const rows = await page.$$eval("#streams tbody tr", (trs) => trs.map((r) => r.textContent));
  assert.ok(rows.some((r) => r.includes(lidar) && r.includes("points lidar_point")), rows.join("\n"));
  assert.ok(rows.some((r) => r.includes(camera) && r.includes("bgr8")), rows.join("\n"));

  // Each view shows a picture that is not blank: many distinct colours, not one flat fill. The
  // page swaps each <img>'s source as frames come, so the check that a picture is loaded and its
  // measurement run in one step inside the page (no new source can start loading in between).
  const spread = async (name) => {
    const measured = await page.waitForFunction((n) => {
      const img = document.querySelector(`.view[data-stream="${n}"] img`);
      if (!img || !img.complete || img.naturalWidth === 0) return null;
      const canvas = document.createElement("canvas");
      canvas.width = img.naturalWidth;
      canvas.height = img.naturalHeight;
      const ctx = canvas.getContext("2d");
      ctx.drawImage(img, 0, 0);
      const { data } = ctx.getImageData(0, 0, canvas.width, canvas.height);
      const colours = new Set();
      let lit = 0;
      for (let i = 0; i < data.length; i += 4) {
        colours.add((data[i] >> 4) * 256 + (data[i + 1] >> 4) * 16 + (data[i + 2] >> 4));
        if (data[i] + data[i + 1] + data[i + 2] > 150) ++lit;
      }
      return { width: canvas.width, height: canvas.height, colours: colours.size, lit };
    }, { timeout: 60_000, polling: 100 }, name);
    return measured.jsonValue();
  };
  const cameraPicture = await spread(camera);
  assert.equal(cameraPicture.width, h.image.width);
  assert.equal(cameraPicture.height, h.image.height);
  assert.ok(cameraPicture.colours > 50, `camera image has only ${cameraPicture.colours} colours`);
  const lidarPicture = await spread(lidar);
  assert.ok(lidarPicture.colours > 20, `top-down view has only ${lidarPicture.colours} colours`);
  assert.ok(lidarPicture.lit > 2000, `top-down view shows only ${lidarPicture.lit} bright pixels`);

  // Intensity colouring is a different picture of the same frame.
  await page.select(`.view[data-stream="${lidar}"] select`, "intensity");
  await page.waitForFunction((n) => {
    const img = document.querySelector(`.view[data-stream="${n}"] img`);
    return img.complete && /color=intensity/.test(img.dataset.url || "");
  }, { timeout: 30_000 }, lidar);

  fs.mkdirSync(artifacts, { recursive: true });
  const shot = path.join(artifacts, "sim_foxglove_page.png");
  await page.screenshot({ path: shot, fullPage: true });
  console.log(`ok: page lists ${lidar} and ${camera}, shows both pictures; screenshot ${shot}`);
} finally {
  await browser.close();
}
await h.stop(server.child);
assert.equal(server.child.exitCode, 0, server.child.stderrText);
console.log("PASS");
process.exit(0);
