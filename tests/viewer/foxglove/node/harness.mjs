// SPDX-License-Identifier: Apache-2.0
// What both Node tests share: the SIM programs they start (real processes, unique stream names,
// all stopped and their streams removed at the end), a small PNG writer for the camera frames,
// and a deadline so a broken server fails the test instead of hanging it.
import { spawn, spawnSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import zlib from "node:zlib";

// Paths come from CTest (tests/viewer/foxglove/CMakeLists.txt).
export const bin = {
  foxglove: need("SIM_FOXGLOVE"),
  replayPcap: need("SIM_REPLAY_PCAP"),
  replayVideo: need("SIM_REPLAY_VIDEO"),
  echo: need("SIM_ECHO"),
  rm: need("SIM_RM"),
  sensorWriter: need("SIM_SENSOR_WRITER"),
};
export const hesaiData = need("SIM_HESAI_DATA");

function need(name) {
  const value = process.env[name];
  if (!value) {
    console.error(`${name} is not set: run this test through ctest (tests/viewer/foxglove).`);
    process.exit(2);
  }
  return value;
}

let counter = 0;
export function uniqueStream(base) {
  return `/${base}_${process.pid}_${counter++}`;
}

const children = new Set();
const streams = new Set();
const dirs = new Set();

export function cleanup() {
  for (const child of children) {
    if (child.exitCode === null && child.signalCode === null) child.kill("SIGKILL");
  }
  if (streams.size > 0) spawnSync(bin.rm, ["--force", ...streams], { stdio: "ignore" });
  for (const dir of dirs) fs.rmSync(dir, { recursive: true, force: true });
}
process.on("exit", cleanup);
for (const signal of ["SIGINT", "SIGTERM"]) {
  process.on(signal, () => process.exit(1));
}

// Fails the test if it is still running after `seconds` (a hang guard, not a timing check).
export function deadline(seconds, what) {
  const timer = setTimeout(() => {
    console.error(`FAIL: ${what} did not finish within ${seconds} s`);
    process.exit(1);
  }, seconds * 1000);
  timer.unref();
}

// A child process whose stdout is read line by line; its stderr is kept for failure messages.
export function start(program, args, { streamNames = [] } = {}) {
  for (const s of streamNames) streams.add(s);
  const child = spawn(program, args, { stdio: ["ignore", "pipe", "pipe"] });
  children.add(child);
  child.stderrText = "";
  child.stderr.on("data", (d) => { child.stderrText += d.toString(); });
  child.lines = [];
  let partial = "";
  const waiters = [];
  child.stdout.on("data", (d) => {
    partial += d.toString();
    let newline;
    while ((newline = partial.indexOf("\n")) >= 0) {
      const line = partial.slice(0, newline);
      partial = partial.slice(newline + 1);
      child.lines.push(line);
      for (const w of [...waiters]) w(line);
    }
  });
  child.onLine = (fn) => waiters.push(fn);
  child.waitForLine = (pattern) => new Promise((resolve, reject) => {
    const found = child.lines.find((l) => pattern.test(l));
    if (found) return resolve(found);
    waiters.push((line) => { if (pattern.test(line)) resolve(line); });
    child.on("exit", (code) => reject(new Error(
      `${path.basename(program)} exited (${code}) before printing ${pattern}: ${child.stderrText}`)));
  });
  return child;
}

export function stop(child) {
  return new Promise((resolve) => {
    if (child.exitCode !== null || child.signalCode !== null) return resolve();
    child.on("exit", () => resolve());
    child.kill("SIGTERM");
  });
}

// sim_foxglove on a free port; resolves to { child, port } once it listens.
export async function startFoxglove(args, streamNames) {
  const child = start(bin.foxglove, ["--port", "0", ...args, ...streamNames]);
  const line = await child.waitForLine(/port \d+/);
  return { child, port: Number(/port (\d+)/.exec(line)[1]) };
}

// The bundled Pandar64 recording, looped (stamps keep increasing across loops).
export function startLidar(stream) {
  return start(bin.replayPcap, [
    path.join(hesaiData, "pandar64_dual.pcap"), "--stream", stream,
    "--calibration", path.join(hesaiData, "pandar64.calibration.csv"),
    "--loop", "--rate", "0.5", "--quiet"], { streamNames: [stream] });
}

export const image = { width: 160, height: 120, frames: 3 };

// Pixel (x, y) of frame k as R, G, B: a gradient and a per-frame blue level, so frames and
// channel order can be told apart.
export function pixel(k, x, y) {
  return [Math.floor((x * 255) / (image.width - 1)), Math.floor((y * 255) / (image.height - 1)),
          (k * 80 + 40) % 256];
}

// A folder of PNG frames for sim_replay_video, written here so the test knows every pixel.
export function writeImageFolder() {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "sim_foxglove_images_"));
  dirs.add(dir);
  for (let k = 0; k < image.frames; ++k) {
    const rows = Buffer.alloc((image.width * 3 + 1) * image.height);
    for (let y = 0; y < image.height; ++y) {
      const row = y * (image.width * 3 + 1);
      rows[row] = 0;  // filter: none
      for (let x = 0; x < image.width; ++x) {
        const [r, g, b] = pixel(k, x, y);
        rows.set([r, g, b], row + 1 + x * 3);
      }
    }
    fs.writeFileSync(path.join(dir, `frame_${k}.png`), png(image.width, image.height, rows));
  }
  return dir;
}

export function startVideo(stream, dir) {
  return start(bin.replayVideo, [dir, "--stream", stream, "--fps", "10", "--loop", "--quiet"],
               { streamNames: [stream] });
}

// sim_echo's JSON lines: what SIM itself holds, to compare the server's messages with. Newer
// sim_echo prints readable lines unless given --json; older ones print JSON and lack the flag.
export function startEcho(stream) {
  const help = spawnSync(bin.echo, ["--help"], { encoding: "utf8" }).stdout || "";
  const json = help.includes("--json") ? ["--json"] : [];
  return start(bin.echo, [stream, "--wait-for-stream", ...json]);
}

// A calibrated camera and a LiDAR, both mounted on base_link (tests/viewer/foxglove/
// sensor_writer.cpp has the scene); the camera is recalibrated at frame `recalibrateAt`.
export const scene = {
  width: 320, height: 240, fx: 200, cx: 160, cy: 120, recalibratedCx: 170,
  cameraFrame: "test_camera_optical", lidarFrame: "test_lidar",
  // Where the wall of points ahead lands in the camera image.
  wall: { left: 120, right: 200, top: 80, bottom: 160 },
  // The clocks: the camera's acquiring (warn, this problem), the LiDAR's locked (ok).
  cameraClockProblem: "the camera's PTP clock is still acquiring; wait until ptp4l reports it locked",
};
export async function startSensorWriter(camera, lidar, recalibrateAt) {
  const args = [camera, lidar];
  if (recalibrateAt !== undefined) args.push(String(recalibrateAt));
  const child = start(bin.sensorWriter, args, { streamNames: [camera, lidar] });
  await child.waitForLine(/^ready$/);
  return child;
}

const crcTable = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});
function crc32(bytes) {
  let c = 0xffffffff;
  for (const b of bytes) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}
function chunk(type, data) {
  const length = Buffer.alloc(4);
  length.writeUInt32BE(data.length);
  const body = Buffer.concat([Buffer.from(type, "ascii"), data]);
  const crc = Buffer.alloc(4);
  crc.writeUInt32BE(crc32(body));
  return Buffer.concat([length, body, crc]);
}
function png(width, height, rows) {
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header[8] = 8;  // bit depth
  header[9] = 2;  // colour type: RGB
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk("IHDR", header), chunk("IDAT", zlib.deflateSync(rows)), chunk("IEND", Buffer.alloc(0)),
  ]);
}
