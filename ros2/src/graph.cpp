// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/graph.hpp"

#include <cstring>

#include "cdr.hpp"
#include "wire.hpp"

namespace sim::ros2 {

namespace {

void write_gid(cdr::Writer& w, const Gid& gid) {
  for (std::uint8_t b : gid) w.u8(b);  // char[16]: bytes, no alignment
}

void write_gids(cdr::Writer& w, std::span<const Gid> gids) {
  w.u32(static_cast<std::uint32_t>(gids.size()));
  for (const Gid& gid : gids) write_gid(w, gid);
}

Gid read_gid(cdr::Reader& r, const char* what) {
  Gid gid{};
  const std::span<const std::byte> bytes = r.fixed(gid.size(), what);
  if (!bytes.empty()) std::memcpy(gid.data(), bytes.data(), gid.size());
  return gid;
}

// A GID sequence; its count is checked against the bytes left before anything is allocated.
void read_gids(cdr::Reader& r, std::vector<Gid>& out, const char* what) {
  const std::uint32_t count = r.u32(what);
  if (!r.ok()) return;
  if (count > r.remaining() / 16) {
    r.fail(what);
    return;
  }
  for (std::uint32_t i = 0; i < count && r.ok(); ++i) out.push_back(read_gid(r, what));
}

}  // namespace

Expected<ParticipantEntities> decode_participant_entities_info(std::span<const std::byte> message) {
  cdr::Reader r(message);
  ParticipantEntities out;
  if (r.encapsulation()) {
    out.participant = read_gid(r, "gid");
    const std::uint32_t nodes = r.u32("node_entities_info_seq");
    if (r.ok() && nodes > max_graph_nodes) {
      return wire::malformed(participant_entities_info_type_name,
                             "it lists " + std::to_string(nodes) + " nodes; at most " +
                                 std::to_string(max_graph_nodes) + " are accepted");
    }
    for (std::uint32_t i = 0; i < nodes && r.ok(); ++i) {
      const std::string_view ns = r.string("node_namespace");
      const std::string_view name = r.string("node_name");
      if (r.ok()) out.nodes.push_back(std::string(ns) + (ns.size() > 1 ? "/" : "") + std::string(name));
      read_gids(r, out.readers, "reader_gid_seq");
      read_gids(r, out.writers, "writer_gid_seq");
    }
  }
  if (!r.ok()) return wire::read_failure(participant_entities_info_type_name, r);
  return out;
}

std::vector<std::byte> encode_participant_entities_info(const Gid& participant,
                                                        std::span<const NodeEntities> nodes) {
  std::size_t bound = 64;
  for (const NodeEntities& n : nodes) {
    bound += 32 + n.node_namespace.size() + n.node_name.size() +
             16 * (n.readers.size() + n.writers.size());
  }
  std::vector<std::byte> out(bound);
  cdr::Writer w(out);
  write_gid(w, participant);
  w.u32(static_cast<std::uint32_t>(nodes.size()));
  for (const NodeEntities& n : nodes) {
    w.string(n.node_namespace);
    w.string(n.node_name);
    write_gids(w, n.readers);
    write_gids(w, n.writers);
  }
  out.resize(w.overflow() ? 0 : w.size());
  return out;
}

}  // namespace sim::ros2
