// Reads an MCAP file with Foxglove's own readers (@mcap/core) and prints what they found, one
// fact per line, for tests/mcap/test_mcap_node.cpp to check:
//   header <profile> <library>
//   summary messages=<n> chunks=<n> schemas=<n> channels=<n> data_crc=<ok|absent>
//   channel <topic> <message encoding> <schema name> <schema encoding> stats=<n> indexed=<n> streamed=<n> ordered=<yes|no> meta:<key>=<value>…
// The indexed reader uses the summary and the chunk and message indexes; the stream reader reads
// the file front to back and checks every chunk CRC. Any error ends the script with exit code 1.
import { open, readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { FileHandleReadable } from "@mcap/nodejs";
import { loadDecompressHandlers } from "@mcap/support";
import { crc32 } from "@foxglove/crc";

const path = process.argv[2];
if (!path) {
  console.error("usage: node read_mcap.mjs FILE.mcap");
  process.exit(2);
}

try {
  const decompressHandlers = await loadDecompressHandlers();
  const handle = await open(path, "r");
  const reader = await McapIndexedReader.Initialize({
    readable: new FileHandleReadable(handle),
    decompressHandlers,
  });

  const indexed = new Map();
  const ordered = new Map();
  const lastTime = new Map();
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    indexed.set(message.channelId, (indexed.get(message.channelId) ?? 0) + 1);
    const previous = lastTime.get(message.channelId) ?? -1n;
    if (message.logTime < previous) ordered.set(message.channelId, false);
    lastTime.set(message.channelId, message.logTime);
  }
  await handle.close();

  const bytes = await readFile(path);
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  stream.append(bytes);
  const streamed = new Map();
  let dataEndOffset;
  for (let record; (record = stream.nextRecord()); ) {
    if (record.type === "Message") {
      streamed.set(record.channelId, (streamed.get(record.channelId) ?? 0) + 1);
    }
  }
  if (!stream.done()) throw new Error("the stream reader did not reach the end of the file");

  // The Data End record sits just before the summary: 1 opcode + 8 length + 4 CRC bytes.
  let dataCrc = "absent";
  if (reader.dataSectionCrc !== undefined && reader.footer.summaryStart > 0n) {
    dataEndOffset = Number(reader.footer.summaryStart) - 13;
    const computed = crc32(bytes.subarray(0, dataEndOffset));
    if (computed !== reader.dataSectionCrc) {
      throw new Error(`data section CRC ${reader.dataSectionCrc} but the bytes give ${computed}`);
    }
    dataCrc = "ok";
  }

  const stats = reader.statistics;
  console.log(`header ${reader.header.profile} ${reader.header.library}`);
  console.log(
    `summary messages=${stats?.messageCount ?? "none"} chunks=${reader.chunkIndexes.length} ` +
      `schemas=${reader.schemasById.size} channels=${reader.channelsById.size} data_crc=${dataCrc}`,
  );
  for (const channel of reader.channelsById.values()) {
    const schema = reader.schemasById.get(channel.schemaId);
    const meta = [...channel.metadata.entries()]
      .filter(([key]) => key.startsWith("sim."))
      .map(([key, value]) => ` meta:${key}=${value}`)
      .join("");
    console.log(
      `channel ${channel.topic} ${channel.messageEncoding} ${schema?.name ?? "-"} ` +
        `${schema?.encoding ?? "-"} stats=${stats?.channelMessageCounts.get(channel.id) ?? 0} ` +
        `indexed=${indexed.get(channel.id) ?? 0} streamed=${streamed.get(channel.id) ?? 0} ` +
        `ordered=${ordered.get(channel.id) === false ? "no" : "yes"} ` +
        `qos=${channel.metadata.has("offered_qos_profiles") ? "yes" : "no"}${meta}`,
    );
  }
} catch (error) {
  console.error(`read_mcap: ${error.message ?? error}`);
  process.exit(1);
}
