// SPDX-License-Identifier: Apache-2.0
// What a stream says about its sensor, as Foxglove gets it: Foxglove's own client, offering only
// the subprotocol foxglove.sdk.v1 (what Foxglove's current apps speak), connects after the
// streams started and finds each camera's calibration beside its image (the namespace Foxglove's
// image panel pairs them by) and every mounting on /tf_static; it subscribes after they were
// sent to nobody and still gets them (latched), decodes them with Foxglove's CDR reader, and
// gets the new calibration when the writer recalibrates. A second client gets them too. Each
// stream's clock is a status of the DiagnosticArray on /diagnostics (Foxglove's Diagnostics panels).
import assert from "node:assert/strict";
import wsProtocol from "@foxglove/ws-protocol";
import rosmsg from "@foxglove/rosmsg";
import serialization from "@foxglove/rosmsg2-serialization";
import WebSocket from "ws";

import * as h from "./harness.mjs";

const { FoxgloveClient } = wsProtocol;
const { parse } = rosmsg;
const { MessageReader } = serialization;

h.deadline(120, "the Foxglove sensor-description test");

// A client offering only `subprotocol`; resolves once the WebSocket is open.
async function connect(port, subprotocol) {
  const ws = new WebSocket(`ws://127.0.0.1:${port}`, [subprotocol]);
  const client = new FoxgloveClient({ ws });
  const state = { channels: new Map(), messages: [] };
  const waiters = [];
  const poke = () => { for (const w of [...waiters]) w(); };
  client.on("advertise", (channels) => { for (const c of channels) state.channels.set(c.id, c); poke(); });
  client.on("message", (m) => { state.messages.push(m); poke(); });
  client.on("error", (e) => { throw e; });
  state.until = (test) => new Promise((resolve) => {
    const check = () => {
      const value = test();
      if (value) { waiters.splice(waiters.indexOf(check), 1); resolve(value); }
    };
    waiters.push(check);
    check();
  });
  state.topic = (name) => [...state.channels.values()].find((c) => c.topic === name);
  await new Promise((resolve, reject) => { ws.on("open", resolve); ws.on("error", reject); });
  return { ws, client, state };
}

const readers = new Map();
function decode(channel, message) {
  if (!readers.has(channel.id)) {
    assert.equal(channel.encoding, "cdr");
    assert.equal(channel.schemaEncoding, "ros2msg");
    readers.set(channel.id, new MessageReader(parse(channel.schema, { ros2: true })));
  }
  const reader = readers.get(channel.id);
  const decoded = reader.readMessage(message.data);
  assert.equal(reader.lastReadHadTrailingBytes(), false, `${channel.topic}: bytes the schema does not describe`);
  return decoded;
}

const camera = h.uniqueStream("fox_sensor_camera");
const lidar = h.uniqueStream("fox_sensor_lidar");
const writer = await h.startSensorWriter(camera, lidar, 40);  // recalibrated ~4 s in
const server = await h.startFoxglove([], [camera, lidar]);
// The streams (and their descriptions) exist before the client connects.
const first = await connect(server.port, "foxglove.sdk.v1");
assert.equal(first.ws.protocol, "foxglove.sdk.v1", "the server did not answer with the subprotocol offered");

const s = first.state;
const imageChannel = await s.until(() => s.topic(`${camera}/image_raw`));
const calibrationChannel = await s.until(() => s.topic(`${camera}/camera_info`));
const transformsChannel = await s.until(() => s.topic("/tf_static"));
const lidarChannel = await s.until(() => s.topic(lidar));
assert.equal(imageChannel.schemaName, "sensor_msgs/msg/Image");
assert.equal(calibrationChannel.schemaName, "foxglove_msgs/msg/CameraCalibration");
assert.equal(transformsChannel.schemaName, "foxglove_msgs/msg/FrameTransforms");
assert.equal(lidarChannel.schemaName, "sensor_msgs/msg/PointCloud2");
// Foxglove pairs an image with the calibration topic that shares its prefix up to the last '/'.
const prefix = (topic) => topic.slice(0, topic.lastIndexOf("/"));
assert.equal(prefix(imageChannel.topic), prefix(calibrationChannel.topic));

// Subscribed well after the server sent them anywhere: latched messages still arrive.
await new Promise((r) => setTimeout(r, 1000));
const subs = {
  calibration: first.client.subscribe(calibrationChannel.id),
  transforms: first.client.subscribe(transformsChannel.id),
  image: first.client.subscribe(imageChannel.id),
  lidar: first.client.subscribe(lidarChannel.id),
};
const received = (state, sub) => state.messages.filter((m) => m.subscriptionId === sub);
await s.until(() => Object.values(subs).every((sub) => received(s, sub).length > 0));

const calibration = decode(calibrationChannel, received(s, subs.calibration)[0]);
assert.equal(calibration.frame_id, h.scene.cameraFrame);
assert.equal(calibration.width, h.scene.width);
assert.equal(calibration.height, h.scene.height);
assert.equal(calibration.distortion_model, "plumb_bob");
assert.deepEqual([...calibration.d], [0, 0, 0, 0, 0]);
assert.deepEqual([...calibration.k], [200, 0, h.scene.cx, 0, 200, h.scene.cy, 0, 0, 1]);
assert.deepEqual([...calibration.r], [1, 0, 0, 0, 1, 0, 0, 0, 1]);
assert.deepEqual([...calibration.p], [200, 0, h.scene.cx, 0, 0, 200, h.scene.cy, 0, 0, 0, 1, 0]);

const { transforms } = decode(transformsChannel, received(s, subs.transforms)[0]);
const byChild = new Map(transforms.map((t) => [t.child_frame_id, t]));
const cameraMount = byChild.get(h.scene.cameraFrame);
const lidarMount = byChild.get(h.scene.lidarFrame);
assert.ok(cameraMount && lidarMount, `transforms: ${JSON.stringify(transforms)}`);
assert.equal(cameraMount.parent_frame_id, "base_link");
assert.deepEqual(cameraMount.translation, { x: 0, y: 0, z: 1.5 });
assert.deepEqual(cameraMount.rotation, { x: -0.5, y: 0.5, z: -0.5, w: 0.5 });
assert.equal(lidarMount.parent_frame_id, "base_link");
assert.deepEqual(lidarMount.translation, { x: 0, y: 0, z: 2 });
assert.ok(Math.abs(lidarMount.rotation.z - Math.SQRT1_2) < 1e-12);

// The frames carry the sensors' frame ids: Foxglove checks the image's against its calibration's.
const image = decode(imageChannel, received(s, subs.image)[0]);
assert.equal(image.header.frame_id, calibration.frame_id);
const cloud = decode(lidarChannel, received(s, subs.lidar)[0]);
assert.equal(cloud.header.frame_id, h.scene.lidarFrame);
console.log("ok: foxglove.sdk.v1 client got the calibration, both mountings and frames in the sensors' frames");

// The clocks: one DiagnosticArray on /diagnostics, a status per stream with its verdict's level.
const diagnosticsChannel = await s.until(() => s.topic("/diagnostics"));
assert.equal(diagnosticsChannel.schemaName, "diagnostic_msgs/msg/DiagnosticArray");
const diagnosticsSub = first.client.subscribe(diagnosticsChannel.id);
const clockStatus = (stream) => s.until(() => received(s, diagnosticsSub)
    .flatMap((m) => decode(diagnosticsChannel, m).status)
    .find((status) => status.name === `sim: ${stream} clock`));
const cameraClock = await clockStatus(camera);
assert.equal(cameraClock.level, 1, "the acquiring camera clock is not WARN");
assert.equal(cameraClock.message, h.scene.cameraClockProblem);
assert.equal(cameraClock.hardware_id, camera);
const cameraValues = new Map(cameraClock.values.map((kv) => [kv.key, kv.value]));
assert.equal(cameraValues.get("clock_source"), "ptp");
assert.equal(cameraValues.get("sync_state"), "acquiring");
assert.equal(cameraValues.get("grandmaster_id"), "00a069.fffe.0b552d");
assert.equal(cameraValues.get("offset_to_host_ns"), "300000");
const lidarClock = await clockStatus(lidar);
assert.equal(lidarClock.level, 0, `the locked LiDAR clock is not OK: ${lidarClock.message}`);
assert.equal(new Map(lidarClock.values.map((kv) => [kv.key, kv.value])).get("sync_state"), "locked");
console.log("ok: /diagnostics carries each stream's clock with the level of its verdict");

// A client that connects and subscribes later still gets the latched messages.
const second = await connect(server.port, "foxglove.websocket.v1");
assert.equal(second.ws.protocol, "foxglove.websocket.v1");
const late = await second.state.until(() => second.state.topic(`${camera}/camera_info`));
const lateTf = await second.state.until(() => second.state.topic("/tf_static"));
const lateSub = second.client.subscribe(late.id);
const lateTfSub = second.client.subscribe(lateTf.id);
await second.state.until(() => received(second.state, lateSub).length > 0 && received(second.state, lateTfSub).length > 0);
assert.equal(decode(late, received(second.state, lateSub)[0]).frame_id, h.scene.cameraFrame);
assert.equal(decode(lateTf, received(second.state, lateTfSub)[0]).transforms.length, 2);
console.log("ok: a later client got the latched calibration and transforms");

// The writer recalibrates (Writer::set_sensor_info): subscribers get the new calibration.
await writer.waitForLine(/^recalibrated$/);
const recalibrated = await s.until(() => received(s, subs.calibration)
    .map((m) => decode(calibrationChannel, m)).find((c) => c.k[2] === h.scene.recalibratedCx));
assert.equal(recalibrated.p[2], h.scene.recalibratedCx);
console.log("ok: the recalibration reached the subscribed client");

first.client.close();
second.client.close();
await h.stop(server.child);
assert.equal(server.child.exitCode, 0, server.child.stderrText);
console.log("PASS");
process.exit(0);
