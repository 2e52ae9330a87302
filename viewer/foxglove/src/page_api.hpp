// SPDX-License-Identifier: Apache-2.0
// The built-in page's small HTTP API, as plain functions: the request target parsed into a path
// and query parameters (fuzzed with the protocol parser), and the stream table as JSON.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "catalog.hpp"

namespace sim::foxglove {

struct Target {
  std::string path;
  std::map<std::string, std::string> query;
};

// "/api/image?stream=%2Fcamera_front" -> {"/api/image", {{"stream", "/camera_front"}}}.
// nullopt for a target that is not an origin-form path or has broken percent-encoding.
std::optional<Target> parse_target(std::string_view target);

// The page's stream table: one object per stream with its health, how it is shown, its sensor's
// frame and calibration, and for a calibrated camera the LiDAR streams whose points can be drawn
// into its image (a chain of `mountings` joins their frames), and its clock ("clock": summary,
// verdict, problem; absent when the writer reports none).
std::string streams_json(const std::vector<StreamEntry>& streams,
                         const std::vector<FrameTransform>& mountings);

// The page itself (page.html, embedded at build time).
extern const char* const kPageHtml;

}  // namespace sim::foxglove
