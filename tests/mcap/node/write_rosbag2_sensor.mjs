// Writes an MCAP file as rosbag2 records a calibrated camera driver, with Foxglove's @mcap/core
// writer and ROS 2 CDR serializer (nothing of SIM): tests/mcap/test_mcap_node.cpp plays it with
// sim_play and checks the calibration and mounting arrive in the SIM stream.
//   /cam/front/image_raw    Image rgb8 4x3, frame cam_front_optical, 5 messages
//   /cam/front/camera_info  CameraInfo with the identical stamps: 4x3 plumb_bob,
//                           d = [-0.2, 0.1, 0, 0, 0.01], k = [500, 0, 2, 0, 501, 1.5, 0, 0, 1],
//                           p = [499, 0, 2, 0, 0, 498, 1.5, 0, 0, 0, 1, 0]
//   /tf_static              one TFMessage (transient_local offered QoS, as rosbag2 writes it):
//                           base_link -> cam_front_optical t = (1.5, 0.25, 2) r = (0, 0, 0.6, 0.8)
//                           base_link -> lidar_top         t = (0, 0, 2.5)    r = (0, 0, 0, 1)
// With "uncalibrated-rig" after the path (review turn 4 M2, M3, M5), as a RealSense driver
// without a calibration records: the images' frame is camera_color_optical_frame, chained
//   base_link -> camera_link (t = (1, 0, 0.5), r = (0, 0, 0.7071, 0.7071), typed to 4 decimals)
//   camera_link -> camera_color_frame (t = (0, 0.015, 0)) -> camera_color_optical_frame
//   (r = (-0.5, 0.5, -0.5, 0.5)), and the CameraInfo has k all zero and no distortion_model.
// Every channel carries topic_type_hash (RIHS01 of sensor_msgs and tf2_msgs as rosidl generates it).
import { open } from "node:fs/promises";
import { McapWriter } from "@mcap/core";
import { FileHandleWritable } from "@mcap/nodejs";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";

const SEPARATOR = "=".repeat(80);
const deps = (...parts) => parts.map(([name, text]) => `${SEPARATOR}\nMSG: ${name}\n${text}`).join("\n");
const HEADER = ["std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id"];
const TIME = ["builtin_interfaces/Time", "int32 sec\nuint32 nanosec"];
const IMAGE = `std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n` +
  `uint32 step\nuint8[] data\n` + deps(HEADER, TIME);
const CAMERA_INFO = `std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n` +
  `float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n` +
  `sensor_msgs/RegionOfInterest roi\n` + deps(HEADER, TIME, ["sensor_msgs/RegionOfInterest",
  "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify"]);
const TF = `geometry_msgs/TransformStamped[] transforms\n` + deps(
  ["geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform"],
  HEADER, TIME,
  ["geometry_msgs/Transform", "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation"],
  ["geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z"],
  ["geometry_msgs/Quaternion", "float64 x\nfloat64 y\nfloat64 z\nfloat64 w"]);

// rosbag2 (Jazzy) offered QoS: a sensor topic, and /tf_static latched.
const qos = (reliability, durability, depth) =>
  `- history: keep_last\n  depth: ${depth}\n  reliability: ${reliability}\n  durability: ${durability}\n` +
  `  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n` +
  `  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n` +
  `  avoid_ros_namespace_conventions: false\n`;
const HASH = {
  image: "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47",
  cameraInfo: "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275",
  tf: "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
};

const handle = await open(process.argv[2], "w");
const writer = new McapWriter({ writable: new FileHandleWritable(handle), chunkSize: 4096 });
await writer.start({ profile: "ros2", library: "write_rosbag2_sensor.mjs" });
const encoder = new TextEncoder();
const channel = async (topic, name, text, metadata) => {
  const schemaId = await writer.registerSchema({ name, encoding: "ros2msg", data: encoder.encode(text) });
  return writer.registerChannel({ topic, messageEncoding: "cdr", schemaId, metadata: new Map(Object.entries(metadata)) });
};
const tfChannel = await channel("/tf_static", "tf2_msgs/msg/TFMessage", TF,
  { offered_qos_profiles: qos("reliable", "transient_local", 1), topic_type_hash: HASH.tf });
const infoChannel = await channel("/cam/front/camera_info", "sensor_msgs/msg/CameraInfo", CAMERA_INFO,
  { offered_qos_profiles: qos("reliable", "volatile", 10), topic_type_hash: HASH.cameraInfo });
const imageChannel = await channel("/cam/front/image_raw", "sensor_msgs/msg/Image", IMAGE,
  { offered_qos_profiles: qos("reliable", "volatile", 10), topic_type_hash: HASH.image });

const start = { sec: 1700000500, nanosec: 0 };
const toNs = (t) => BigInt(t.sec) * 1000000000n + BigInt(t.nanosec);
const rig = process.argv[3] === "uncalibrated-rig";
const cameraFrame = rig ? "camera_color_optical_frame" : "cam_front_optical";
const mount = (parent, child, t, r) => ({ header: { stamp: start, frame_id: parent }, child_frame_id: child,
  transform: { translation: { x: t[0], y: t[1], z: t[2] }, rotation: { x: r[0], y: r[1], z: r[2], w: r[3] } } });
const cameraMountings = rig ? [
  mount("base_link", "camera_link", [1, 0, 0.5], [0, 0, 0.7071, 0.7071]),
  mount("camera_link", "camera_color_frame", [0, 0.015, 0], [0, 0, 0, 1]),
  mount("camera_color_frame", "camera_color_optical_frame", [0, 0, 0], [-0.5, 0.5, -0.5, 0.5]),
] : [mount("base_link", "cam_front_optical", [1.5, 0.25, 2], [0, 0, 0.6, 0.8])];
const tf = new MessageWriter(parse(TF, { ros2: true })).writeMessage({ transforms: [
  ...cameraMountings,
  { header: { stamp: start, frame_id: "base_link" }, child_frame_id: "lidar_top",
    transform: { translation: { x: 0, y: 0, z: 2.5 }, rotation: { x: 0, y: 0, z: 0, w: 1 } } },
] });
await writer.addMessage({ channelId: tfChannel, sequence: 0, logTime: toNs(start), publishTime: toNs(start), data: tf });

const infoWriter = new MessageWriter(parse(CAMERA_INFO, { ros2: true }));
const imageWriter = new MessageWriter(parse(IMAGE, { ros2: true }));
for (let m = 0; m < 5; ++m) {
  const stamp = { sec: start.sec + 1, nanosec: m * 100000000 };
  const header = { stamp, frame_id: cameraFrame };
  const time = toNs(stamp);
  const info = infoWriter.writeMessage({
    header, height: 3, width: 4, distortion_model: rig ? "" : "plumb_bob", d: rig ? [] : [-0.2, 0.1, 0, 0, 0.01],
    k: rig ? new Array(9).fill(0) : [500, 0, 2, 0, 501, 1.5, 0, 0, 1],
    r: rig ? new Array(9).fill(0) : [1, 0, 0, 0, 1, 0, 0, 0, 1],
    p: rig ? new Array(12).fill(0) : [499, 0, 2, 0, 0, 498, 1.5, 0, 0, 0, 1, 0], binning_x: 0, binning_y: 0,
    roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false },
  });
  const pixels = new Uint8Array(4 * 3 * 3).map((_, j) => (m + j) % 256);
  const image = imageWriter.writeMessage({ header, height: 3, width: 4, encoding: "rgb8", is_bigendian: 0,
                                           step: 12, data: pixels });
  // rosbag2 logs each message when it arrives: the image first here, its calibration just after.
  await writer.addMessage({ channelId: imageChannel, sequence: m, logTime: time + 1000n, publishTime: time, data: image });
  await writer.addMessage({ channelId: infoChannel, sequence: m, logTime: time + 2000n, publishTime: time, data: info });
}
await writer.end();
await handle.close();
