// SPDX-License-Identifier: Apache-2.0
// The soak's viewer: Foxglove's own WebSocket client (@foxglove/ws-protocol over `ws`, and its CDR
// reader, installed by tests/viewer/foxglove/node/install.sh) subscribed to some of sim_foxglove's
// channels, and the built-in page fetched as a browser does (/, /api/streams, the newest image and
// top-down view), every two seconds.
//
//   node soak_foxglove_client.mjs PORT TOPIC…
//
// Follows channels that are re-advertised (a stream replaced with another layout). One JSON line
// per second: messages per stream, stamps that went backwards, undecodable messages, page fetches
// that failed. Exits 1 if the server closes the connection; SIGTERM ends it with exit 0.
import http from "node:http";
import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";

const here = path.dirname(fileURLToPath(import.meta.url));
const require = createRequire(path.join(here, "../viewer/foxglove/node/package.json"));
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const WebSocket = require("ws");

const [port, ...topics] = process.argv.slice(2);
if (!port || topics.length === 0) {
  console.error("usage: node soak_foxglove_client.mjs PORT TOPIC...");
  process.exit(2);
}
const base = `http://127.0.0.1:${port}`;
const counters = Object.fromEntries(topics.map((t) => [t, { messages: 0, backwards: 0, undecodable: 0, subscriptions: 0 }]));
const page = { fetches: 0, failures: 0, images: 0, image_unavailable: 0 };
const lastStamp = new Map();
const subscriptions = new Map();  // subscription id -> { topic, reader }
const subscribedChannel = new Map();  // topic -> channel id

function print(final) {
  console.log(JSON.stringify({ kind: "stats", role: "foxglove", final, topics: counters, page }));
}
function violation(what, topic, detail) {
  console.log(JSON.stringify({ kind: "violation", what, stream: topic, detail }));
}

const client = new FoxgloveClient({ ws: new WebSocket(`ws://127.0.0.1:${port}`, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
// The stream a channel carries frames of: LiDAR frames on the stream's own name, images on
// STREAM/image_raw (or STREAM/compressed; before the topics moved, on the stream's name too).
// Calibration and transform channels are not frames.
function streamOf(topic) {
  for (const suffix of ["", "/image_raw", "/compressed"]) {
    if (topic.endsWith(suffix) && topics.includes(topic.slice(0, topic.length - suffix.length))) {
      return topic.slice(0, topic.length - suffix.length);
    }
  }
  return undefined;
}

client.on("advertise", (channels) => {
  for (const c of channels) {
    const stream = streamOf(c.topic);
    if (!stream || subscribedChannel.get(c.topic) === c.id) continue;
    const reader = new MessageReader(parse(c.schema, { ros2: true }));
    subscriptions.set(client.subscribe(c.id), { topic: stream, reader });
    subscribedChannel.set(c.topic, c.id);
    counters[stream].subscriptions += 1;
  }
});
client.on("unadvertise", (ids) => {
  for (const [topic, id] of subscribedChannel) if (ids.includes(id)) subscribedChannel.delete(topic);
});
client.on("message", (m) => {
  const sub = subscriptions.get(m.subscriptionId);
  if (!sub) return;
  const c = counters[sub.topic];
  c.messages += 1;
  let stamp;
  try {
    const msg = sub.reader.readMessage(m.data);
    stamp = BigInt(msg.header.stamp.sec) * 1_000_000_000n + BigInt(msg.header.stamp.nanosec);
  } catch (e) {
    c.undecodable += 1;
    violation("undecodable", sub.topic, String(e));
    return;
  }
  // A restarted writer stamps with the wall clock again, so stamps keep rising across restarts.
  if (lastStamp.has(sub.topic) && stamp < lastStamp.get(sub.topic)) {
    c.backwards += 1;
    violation("backwards", sub.topic, `${stamp} after ${lastStamp.get(sub.topic)}`);
  }
  lastStamp.set(sub.topic, stamp);
});
client.on("error", (e) => violation("websocket_error", "", String(e)));
client.on("close", () => {
  if (stopping) return;
  violation("websocket_closed", "", "the server closed the connection");
  print(true);
  process.exit(1);
});

// One GET on a connection of its own (no keep-alive pool), as a browser tab opened and closed
// would: the status and the body's length, or the error.
function get(target) {
  return new Promise((resolve) => {
    const request = http.get(base + target, { agent: false, timeout: 10_000 }, (response) => {
      let length = 0;
      response.on("data", (chunk) => { length += chunk.length; });
      response.on("end", () => resolve({ status: response.statusCode, length }));
      response.on("error", (e) => resolve({ error: String(e) }));
    });
    request.on("timeout", () => request.destroy(new Error("no answer within 10 s")));
    request.on("error", (e) => resolve({ error: String(e) }));
  });
}

async function fetchPage() {
  const wanted = [["/", true], ["/api/streams", true]];
  for (const t of topics) wanted.push([`/api/${t.includes("lidar") ? "topdown" : "image"}?stream=${encodeURIComponent(t)}`, false]);
  for (const [target, mustServe] of wanted) {
    page.fetches += 1;
    const r = await get(target);
    if (r.status === 200 && r.length > 0) {
      if (!mustServe) page.images += 1;
    } else if (!mustServe && (r.status === 503 || r.status === 404)) {
      // The stream is between writers, removed, or a LiDAR stream for now (layout replaced).
      page.image_unavailable += 1;
    } else {
      page.failures += 1;
      violation("page", "", `${target}: ${r.error ?? `HTTP ${r.status}`}`);
    }
  }
}

let stopping = false;
let fetching = false;  // one round of fetches at a time, however slow the server is
const timers = [
  setInterval(() => print(false), 1000),
  setInterval(() => {
    if (fetching) return;
    fetching = true;
    void fetchPage().finally(() => { fetching = false; });
  }, 2000),
];
for (const signal of ["SIGTERM", "SIGINT"]) {
  process.on(signal, () => {
    stopping = true;
    for (const t of timers) clearInterval(t);
    print(true);
    client.close();
    process.exit(0);
  });
}
