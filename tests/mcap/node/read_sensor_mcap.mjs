// Reads what an MCAP file says about its sensors with Foxglove's own libraries (@mcap/core's
// indexed reader, @foxglove/rosmsg2-serialization decoding with each channel's own schema) and
// prints one fact per line for tests/mcap/test_mcap_node.cpp:
//   channel <topic> <schema name> hash=<topic_type_hash or -> durability=<offered durability or ->
//   image <topic> <sec>.<nanosec> <frame_id>
//   camera_info <topic> <sec>.<nanosec> <frame_id> <width>x<height> <distortion model> d=<…> k=<…> p=<…>
//   tf <parent> <child> t=<x,y,z> r=<x,y,z,w>
//   diagnostic <topic> <sec>.<nanosec> level=<n> hw=<hardware_id> <key>=<value>… "<name>" "<message>"
// Any error ends the script with exit code 1.
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { FileHandleReadable } from "@mcap/nodejs";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const path = process.argv[2];
try {
  const handle = await open(path, "r");
  const reader = await McapIndexedReader.Initialize({
    readable: new FileHandleReadable(handle),
    decompressHandlers: await loadDecompressHandlers(),
  });
  const readers = new Map();
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    const qos = channel.metadata.get("offered_qos_profiles") ?? "";
    const durability = /durability: *(\S+)/.exec(qos)?.[1] ?? "-";
    console.log(`channel ${channel.topic} ${schema?.name ?? "-"} ` +
                `hash=${channel.metadata.get("topic_type_hash") ?? "-"} durability=${durability}`);
    if (schema) {
      const text = new TextDecoder().decode(schema.data);
      readers.set(channel.id, { name: schema.name, topic: channel.topic,
                                reader: new MessageReader(parse(text, { ros2: true })) });
    }
  }
  const stamp = (h) => `${h.stamp.sec}.${String(h.stamp.nanosec).padStart(9, "0")}`;
  const list = (a) => Array.from(a).join(",");
  for await (const message of reader.readMessages()) {
    const r = readers.get(message.channelId);
    if (!r) continue;
    if (r.name === "sensor_msgs/msg/Image") {
      const m = r.reader.readMessage(message.data);
      console.log(`image ${r.topic} ${stamp(m.header)} ${m.header.frame_id}`);
    } else if (r.name === "sensor_msgs/msg/CameraInfo") {
      const m = r.reader.readMessage(message.data);
      console.log(`camera_info ${r.topic} ${stamp(m.header)} ${m.header.frame_id} ${m.width}x${m.height} ` +
                  `${m.distortion_model} d=${list(m.d)} k=${list(m.k)} p=${list(m.p)}`);
    } else if (r.name === "diagnostic_msgs/msg/DiagnosticArray") {
      const m = r.reader.readMessage(message.data);
      for (const s of m.status) {
        const values = s.values.map((kv) => `${kv.key}=${kv.value.replaceAll(" ", "_")}`).join(" ");
        console.log(`diagnostic ${r.topic} ${stamp(m.header)} level=${s.level} hw=${s.hardware_id} ` +
                    `${values} "${s.name}" "${s.message}"`);
      }
    } else if (r.name === "tf2_msgs/msg/TFMessage") {
      const m = r.reader.readMessage(message.data);
      for (const t of m.transforms) {
        const { translation: v, rotation: q } = t.transform;
        console.log(`tf ${t.header.frame_id} ${t.child_frame_id} t=${v.x},${v.y},${v.z} r=${q.x},${q.y},${q.z},${q.w}`);
      }
    }
  }
  await handle.close();
} catch (error) {
  console.error(`read_sensor_mcap: ${error.message ?? error}`);
  process.exit(1);
}
