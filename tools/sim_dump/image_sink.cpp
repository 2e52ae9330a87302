// SPDX-License-Identifier: Apache-2.0
// Image streams: the place PNG writing plugs in. The camera work replaces this with a sink
// that writes 8/16-bit mono and colour images (and decodes MJPEG) to PNG; until then image
// streams are refused up front with a sentence saying so, rather than dumped as raw bytes.
#include "frame_sink.hpp"

namespace sim::dump {

Expected<std::unique_ptr<FrameSink>> make_image_sink(const ImageLayout& layout,
                                                     const SinkOptions& /*options*/) {
  return Error{ErrorCode::invalid_argument,
               "the stream holds images (" + std::to_string(layout.width) + "x" +
                   std::to_string(layout.height) + " " + to_string(layout.format) +
                   "), and this sim_dump writes only LiDAR frames as PCD and raw streams as "
                   ".bin; PNG output for images is not built yet."};
}

}  // namespace sim::dump
