// SPDX-License-Identifier: Apache-2.0
// The naming rules of SIM streams, so a program can refuse a bad name before it opens any
// device, port or file: the same rules Writer::create and Reader::open apply.
#pragma once

#include <string>
#include <string_view>

namespace sim {

// Empty when `name` is a valid stream name ("/lidar_top"); otherwise one sentence saying what is
// wrong and what to do.
std::string stream_name_problem(std::string_view name);

}  // namespace sim
