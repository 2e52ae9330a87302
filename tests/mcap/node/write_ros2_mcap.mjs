// Writes a ROS 2 MCAP file the way tools outside SIM do: Foxglove's @mcap/core writer and its
// ROS 2 CDR serializer (@foxglove/rosmsg2-serialization), standard sensor_msgs schemas, no SIM
// metadata. tests/mcap/test_play_foreign.cpp plays it with sim_play and checks every value:
//   /ext/cloud  PointCloud2, 5 messages of 100 points, point_step 32: x y z (FLOAT32 at 0, 4, 8),
//               intensity (FLOAT32 at 16), ring (UINT16 at 20); point k of message m:
//               x = m + k/2, y = -k, z = k/4, intensity = k, ring = k % 64
//   /ext/image  Image rgb8 4x3, step 16 (4 bytes of row padding); byte j of message m = (3m + j) % 256
//   message m stamped sec 1700000100 + m, nanosec 5000; logged at the same time (image: + 1 ms)
import { open } from "node:fs/promises";
import { McapWriter } from "@mcap/core";
import { FileHandleWritable } from "@mcap/nodejs";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";

const SEPARATOR = "=".repeat(80);
const HEADER = `builtin_interfaces/Time stamp\nstring frame_id`;
const TIME = `int32 sec\nuint32 nanosec`;
const POINT_FIELD =
  `uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\n` +
  `uint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count`;
const deps = (...parts) => parts.map(([name, text]) => `${SEPARATOR}\nMSG: ${name}\n${text}`).join("\n");
const CLOUD =
  `std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n` +
  `bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n` +
  deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME], ["sensor_msgs/PointField", POINT_FIELD]);
const IMAGE =
  `std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n` +
  `uint32 step\nuint8[] data\n` + deps(["std_msgs/Header", HEADER], ["builtin_interfaces/Time", TIME]);

const path = process.argv[2];
const handle = await open(path, "w");
const writer = new McapWriter({ writable: new FileHandleWritable(handle), chunkSize: 4096 });
await writer.start({ profile: "ros2", library: "write_ros2_mcap.mjs" });
const qos = { offered_qos_profiles: "" };
const cloudSchema = await writer.registerSchema({
  name: "sensor_msgs/msg/PointCloud2", encoding: "ros2msg", data: new TextEncoder().encode(CLOUD) });
const imageSchema = await writer.registerSchema({
  name: "sensor_msgs/msg/Image", encoding: "ros2msg", data: new TextEncoder().encode(IMAGE) });
const cloudChannel = await writer.registerChannel({
  topic: "/ext/cloud", messageEncoding: "cdr", schemaId: cloudSchema, metadata: new Map(Object.entries(qos)) });
const imageChannel = await writer.registerChannel({
  topic: "/ext/image", messageEncoding: "cdr", schemaId: imageSchema, metadata: new Map(Object.entries(qos)) });
const cloudWriter = new MessageWriter(parse(CLOUD, { ros2: true }));
const imageWriter = new MessageWriter(parse(IMAGE, { ros2: true }));

const points = 100;
const step = 32;
for (let m = 0; m < 5; ++m) {
  const stamp = { sec: 1700000100 + m, nanosec: 5000 };
  const time = BigInt(stamp.sec) * 1000000000n + BigInt(stamp.nanosec);
  const data = new Uint8Array(points * step);
  const view = new DataView(data.buffer);
  for (let k = 0; k < points; ++k) {
    view.setFloat32(k * step + 0, m + k / 2, true);
    view.setFloat32(k * step + 4, -k, true);
    view.setFloat32(k * step + 8, k / 4, true);
    view.setFloat32(k * step + 16, k, true);
    view.setUint16(k * step + 20, k % 64, true);
  }
  const cloud = cloudWriter.writeMessage({
    header: { stamp, frame_id: "ext_lidar" }, height: 1, width: points,
    fields: [
      { name: "x", offset: 0, datatype: 7, count: 1 }, { name: "y", offset: 4, datatype: 7, count: 1 },
      { name: "z", offset: 8, datatype: 7, count: 1 }, { name: "intensity", offset: 16, datatype: 7, count: 1 },
      { name: "ring", offset: 20, datatype: 4, count: 1 },
    ],
    is_bigendian: false, point_step: step, row_step: step * points, data, is_dense: true,
  });
  await writer.addMessage({ channelId: cloudChannel, sequence: m, logTime: time, publishTime: time, data: cloud });

  const pixels = new Uint8Array(16 * 3);
  for (let j = 0; j < pixels.length; ++j) pixels[j] = (3 * m + j) % 256;
  const image = imageWriter.writeMessage({
    header: { stamp, frame_id: "ext_camera" }, height: 3, width: 4, encoding: "rgb8", is_bigendian: 0,
    step: 16, data: pixels,
  });
  await writer.addMessage({
    channelId: imageChannel, sequence: m, logTime: time + 1000000n, publishTime: time, data: image });
}
await writer.end();
await handle.close();
