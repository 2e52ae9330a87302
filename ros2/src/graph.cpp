// SPDX-License-Identifier: Apache-2.0
#include "sim/ros2/graph.hpp"

#include "cdr.hpp"

namespace sim::ros2 {

namespace {

void write_gid(cdr::Writer& w, const Gid& gid) {
  for (std::uint8_t b : gid) w.u8(b);  // char[16]: bytes, no alignment
}

void write_gids(cdr::Writer& w, std::span<const Gid> gids) {
  w.u32(static_cast<std::uint32_t>(gids.size()));
  for (const Gid& gid : gids) write_gid(w, gid);
}

}  // namespace

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
