// SPDX-License-Identifier: Apache-2.0
// sim_foxglove as Foxglove sees it: Foxglove's own WebSocket client (@foxglove/ws-protocol over
// `ws`) connects, subscribes, and every message is decoded with Foxglove's own CDR deserializer
// (@foxglove/rosmsg2-serialization with the schema text the server advertised). The streams
// are fed by the real replay tools: the Pandar64 recording (sim_replay_pcap) and a folder of PNG
// frames (sim_replay_video); sim_echo reports what SIM itself holds, to compare with.
import assert from "node:assert/strict";
import { spawnSync } from "node:child_process";
import wsProtocol from "@foxglove/ws-protocol";
import rosmsg from "@foxglove/rosmsg";
import serialization from "@foxglove/rosmsg2-serialization";
import WebSocket from "ws";

import * as h from "./harness.mjs";

// CommonJS packages: named exports through their default export.
const { FoxgloveClient } = wsProtocol;
const { parse } = rosmsg;
const { MessageReader } = serialization;

h.deadline(150, "the Foxglove client test");

function stampNs(header) {
  return BigInt(header.stamp.sec) * 1_000_000_000n + BigInt(header.stamp.nanosec);
}

// A connected client that records everything the server says.
function connect(port) {
  const client = new FoxgloveClient({
    ws: new WebSocket(`ws://127.0.0.1:${port}`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]),
  });
  const state = { serverInfo: null, channels: new Map(), removed: [], statuses: [], messages: [] };
  const waiters = [];
  const poke = () => { for (const w of [...waiters]) w(); };
  client.on("serverInfo", (info) => { state.serverInfo = info; poke(); });
  client.on("advertise", (channels) => {
    for (const c of channels) state.channels.set(c.id, c);
    poke();
  });
  client.on("unadvertise", (ids) => {
    for (const id of ids) { state.channels.delete(id); state.removed.push(id); }
    poke();
  });
  client.on("status", (s) => { state.statuses.push(s); poke(); });
  client.on("message", (m) => { state.messages.push(m); poke(); });
  client.on("error", (e) => { throw e; });
  // Resolves when `test()` returns something truthy after any event.
  state.until = (what, test) => new Promise((resolve) => {
    const check = () => {
      const value = test();
      if (value) {
        waiters.splice(waiters.indexOf(check), 1);
        resolve(value);
      }
    };
    waiters.push(check);
    check();
  });
  state.topic = (name) => [...state.channels.values()].find((c) => c.topic === name);
  return { client, state };
}

function readerFor(channel) {
  assert.equal(channel.encoding, "cdr");
  assert.equal(channel.schemaEncoding, "ros2msg");
  return new MessageReader(parse(channel.schema, { ros2: true }));
}

function decode(reader, message) {
  const decoded = reader.readMessage(message.data);
  assert.equal(reader.lastReadHadTrailingBytes(), false, "the message has bytes its schema does not describe");
  return decoded;
}

// --- 0. Rates too small to mean anything are a usage error (review L3), not every frame. ------
for (const rate of ["1e-12", "-1"]) {
  const run = spawnSync(h.bin.foxglove, ["--port", "0", "--max-rate", rate], { encoding: "utf8", timeout: 20_000 });
  assert.equal(run.status, 2, `--max-rate ${rate}: exit ${run.status}, ${run.stderr}`);
  assert.match(run.stderr, /--max-rate/);
}

const lidar = h.uniqueStream("fox_lidar");
const camera = h.uniqueStream("fox_camera");
const images = h.writeImageFolder();

// --- 1. Advertise, subscribe, decode: both streams, every message checked. -----------------
h.startLidar(lidar);
const echo = h.startEcho(lidar);
const simSizes = new Map();  // stamp -> frame bytes, from SIM itself
echo.onLine((line) => {
  // Read the stamp as text: nanoseconds since the epoch do not fit a JSON (double) number.
  const stamp = /"stamp_ns":(-?\d+)/.exec(line);
  if (stamp) simSizes.set(BigInt(stamp[1]), JSON.parse(line).size);
});
const server = await h.startFoxglove([], [lidar, camera]);
const { client, state } = connect(server.port);

await state.until("serverInfo", () => state.serverInfo);
assert.equal(state.serverInfo.name, "sim_foxglove");
const lidarChannel = await state.until("lidar advertised", () => state.topic(lidar));
assert.equal(lidarChannel.schemaName, "sensor_msgs/msg/PointCloud2");
// Images get a namespace of their own (for Foxglove to pair them with a calibration).
const cameraTopic = `${camera}/image_raw`;
assert.equal(state.topic(cameraTopic), undefined, "a stream that does not exist yet is advertised");

// The camera starts after the client is connected: the server must advertise it as it appears.
h.startVideo(camera, images);
const cameraChannel = await state.until("camera advertised", () => state.topic(cameraTopic));
assert.equal(cameraChannel.schemaName, "sensor_msgs/msg/Image");

const lidarSub = client.subscribe(lidarChannel.id);
const cameraSub = client.subscribe(cameraChannel.id);
const lidarReader = readerFor(lidarChannel);
const cameraReader = readerFor(cameraChannel);

const wanted = 6;
await state.until("messages on both channels", () =>
  state.messages.filter((m) => m.subscriptionId === lidarSub).length >= wanted &&
  state.messages.filter((m) => m.subscriptionId === cameraSub).length >= wanted);

let matchedWithSim = 0;
let lastLidarStamp = -1n;
let lastCameraStamp = -1n;
for (const m of state.messages) {
  if (m.subscriptionId === lidarSub) {
    const cloud = decode(lidarReader, m);
    const names = cloud.fields.map((f) => f.name);
    for (const f of ["x", "y", "z", "intensity"]) assert.ok(names.includes(f), `no field ${f}`);
    assert.equal(cloud.point_step, 24);
    assert.equal(cloud.height, 1);
    assert.equal(cloud.row_step, cloud.width * cloud.point_step);
    assert.equal(cloud.data.length, cloud.width * cloud.point_step);
    assert.ok(cloud.width > 10_000, `a Pandar64 revolution has far more than ${cloud.width} points`);
    const stamp = stampNs(cloud.header);
    assert.equal(m.timestamp, stamp, "the message timestamp is not the frame's stamp");
    assert.ok(stamp > lastLidarStamp, "LiDAR stamps went backwards");
    lastLidarStamp = stamp;
    // The same frame as SIM holds it: same stamp, same number of points.
    if (simSizes.has(stamp)) {
      assert.equal(cloud.width, simSizes.get(stamp) / 24, "point count differs from the SIM frame");
      ++matchedWithSim;
    }
    // A point decoded from the CDR bytes is a real return: finite, within the Pandar64's range.
    const view = new DataView(cloud.data.buffer, cloud.data.byteOffset, cloud.data.byteLength);
    const x = view.getFloat32(0, true), y = view.getFloat32(4, true), z = view.getFloat32(8, true);
    const range = Math.hypot(x, y, z);
    assert.ok(range >= 0.3 && range <= 200, `first point at ${range} m`);
  } else if (m.subscriptionId === cameraSub) {
    const img = decode(cameraReader, m);
    assert.equal(img.width, h.image.width);
    assert.equal(img.height, h.image.height);
    assert.equal(img.encoding, "bgr8");
    assert.equal(img.step, h.image.width * 3);
    assert.equal(img.data.length, img.step * img.height);
    const stamp = stampNs(img.header);
    assert.equal(m.timestamp, stamp);
    assert.ok(stamp > lastCameraStamp, "camera stamps went backwards");
    lastCameraStamp = stamp;
    // Which frame it is shows in its blue level; then every sampled pixel must match the PNG.
    const k = [0, 1, 2].find((i) => h.pixel(i, 0, 0)[2] === img.data[0]);
    assert.notEqual(k, undefined, `blue level ${img.data[0]} is not one of the frames`);
    for (const [x, y] of [[0, 0], [10, 20], [159, 119], [80, 60]]) {
      const [r, g, b] = h.pixel(k, x, y);
      const at = y * img.step + x * 3;
      assert.deepEqual([...img.data.subarray(at, at + 3)], [b, g, r], `pixel ${x},${y}`);
    }
  }
}
assert.ok(matchedWithSim >= 3, `only ${matchedWithSim} clouds matched a frame sim_echo saw`);
console.log(`ok: ${state.messages.length} messages decoded with Foxglove's CDR reader; ` +
            `${matchedWithSim} clouds matched SIM's frames point for point`);

// --- 2. Bad requests get an error status; the connection stays usable. ---------------------
const statusesBefore = state.statuses.length;
client.subscribe(987654);  // a channel that was never advertised
await state.until("status for unknown channel", () =>
  state.statuses.slice(statusesBefore).find((s) => /987654/.test(s.message)));
assert.equal(state.statuses.at(-1).level, 2);

// --- 3. Unsubscribe stops the channel's messages. -------------------------------------------
client.unsubscribe(cameraSub);
await new Promise((r) => setTimeout(r, 500));  // what was already on the wire may still arrive
const afterUnsubscribe = state.messages.length;
await state.until("more LiDAR messages", () =>
  state.messages.slice(afterUnsubscribe).filter((m) => m.subscriptionId === lidarSub).length >= 2);
assert.equal(state.messages.slice(afterUnsubscribe).filter((m) => m.subscriptionId === cameraSub).length, 0,
             "camera messages kept coming after unsubscribe");
console.log("ok: error status for an unknown channel; unsubscribe stops the camera messages");

// --- 4. A removed stream is unadvertised. ---------------------------------------------------
// sim_rm removes the region while its writer still runs: the name is gone for every reader.
spawnSync(h.bin.rm, ["--force", camera], { stdio: "ignore" });
await state.until("camera unadvertised", () => state.removed.includes(cameraChannel.id));
console.log("ok: the removed camera stream was unadvertised");
client.close();

// --- 5. --compress jpeg: images as CompressedImage, JPEG bytes Foxglove can show. -----------
const camera2 = h.uniqueStream("fox_camera_jpeg");
h.startVideo(camera2, images);
const jpegServer = await h.startFoxglove(["--compress", "jpeg:70", "--max-rate", "5"], [camera2]);
const second = connect(jpegServer.port);
const jpegChannel = await second.state.until("jpeg channel", () => second.state.topic(`${camera2}/compressed`));
assert.equal(jpegChannel.schemaName, "sensor_msgs/msg/CompressedImage");
const jpegSub = second.client.subscribe(jpegChannel.id);
const jpegReader = readerFor(jpegChannel);
await second.state.until("jpeg messages", () =>
  second.state.messages.filter((m) => m.subscriptionId === jpegSub).length >= 3);
for (const m of second.state.messages.filter((m) => m.subscriptionId === jpegSub)) {
  const img = decode(jpegReader, m);
  assert.equal(img.format, "jpeg");
  assert.deepEqual([img.data[0], img.data[1]], [0xff, 0xd8], "not a JPEG (no SOI marker)");
  assert.deepEqual([img.data.at(-2), img.data.at(-1)], [0xff, 0xd9], "JPEG without EOI marker");
  assert.ok(img.data.length < h.image.width * h.image.height * 3, "JPEG larger than the raw image");
}
console.log("ok: --compress jpeg sends sensor_msgs/msg/CompressedImage JPEG frames");
second.client.close();

await h.stop(server.child);
await h.stop(jpegServer.child);
assert.equal(server.child.exitCode, 0, `sim_foxglove exited with ${server.child.exitCode}: ${server.child.stderrText}`);
assert.equal(jpegServer.child.exitCode, 0);
console.log("PASS");
process.exit(0);
