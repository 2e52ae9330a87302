// SPDX-License-Identifier: Apache-2.0
// What every message of this layer shares on the wire: the std_msgs/Header at its start, and the
// sentences for bad input. Used by encode.cpp, decode.cpp and metadata.cpp.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "cdr.hpp"
#include "sim/result.hpp"
#include "sim/ros2/encode.hpp"
#include "sim/ros2/message.hpp"

namespace sim::ros2::wire {

inline Error invalid(std::string message) {
  return Error{ErrorCode::invalid_argument, std::move(message)};
}

// Why `header` cannot be serialized, if it cannot.
inline std::optional<Error> header_problem(const Header& header) {
  if (header.frame_id.size() > max_frame_id_length) {
    return invalid("the frame_id is " + std::to_string(header.frame_id.size()) +
                   " characters long; use at most " + std::to_string(max_frame_id_length));
  }
  if (header.frame_id.find('\0') != std::string_view::npos) {
    return invalid("the frame_id contains a NUL character; use a plain name such as lidar_top");
  }
  return std::nullopt;
}

inline void write_header(cdr::Writer& w, const Header& header) {
  w.i32(header.stamp.sec);
  w.u32(header.stamp.nanosec);
  w.string(header.frame_id);
}

inline Header read_header(cdr::Reader& r) {
  Header h;
  h.stamp.sec = r.i32("header.stamp.sec");
  h.stamp.nanosec = r.u32("header.stamp.nanosec");
  h.frame_id = r.string("header.frame_id");
  return h;
}

inline Error malformed(std::string_view type_name, std::string why) {
  return invalid("dropped a malformed " + std::string(type_name) + ": " + std::move(why));
}
inline Error malformed(MessageType type, std::string why) {
  return malformed(ros_type_name(type), std::move(why));
}

// The sentence for a failed read: the reader's own sentence, or the field that failed.
template <typename Type>
Error read_failure(Type type, const cdr::Reader& r) {
  if (r.failure_is_sentence()) return malformed(type, r.failure());
  return malformed(type, std::string("its field '") + r.failure() +
                             "' runs past the end of the message or is not a valid CDR value; the "
                             "publisher sent bad bytes");
}

// The sentence for a stamp whose nanoseconds are not below one second (L3 of the bridge review:
// this used to read as "runs past the end of the message").
inline std::optional<Error> stamp_problem(std::string_view type_name, const Header& header) {
  if (header.stamp.nanosec < 1'000'000'000u) return std::nullopt;
  return malformed(type_name, "its header.stamp.nanosec is " +
                                  std::to_string(header.stamp.nanosec) +
                                  ", not below 1000000000; the publisher sent a bad stamp");
}

}  // namespace sim::ros2::wire
