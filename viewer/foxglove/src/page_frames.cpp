// SPDX-License-Identifier: Apache-2.0
#include "page_frames.hpp"

#include <cstdio>

namespace sim::foxglove {

std::shared_ptr<PageFrames::Entry> PageFrames::entry(const std::string& stream) {
  std::lock_guard lock(mutex_);
  auto& e = entries_[stream];
  if (!e) e = std::make_shared<Entry>();
  return e;
}

void PageFrames::keep_only(const std::set<std::string>& names) {
  std::lock_guard lock(mutex_);
  std::erase_if(entries_, [&](const auto& kv) { return !names.contains(kv.first); });
}

std::optional<Error> PageFrames::refresh(Entry& e, const std::string& stream) const {
  if (!e.reader) {
    auto opened = Reader::open(stream, {.trust = trust_});
    if (!opened) return opened.error();
    e.reader.emplace(std::move(opened.value()));
  }
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (e.frame.size() < e.reader->capacity()) e.frame.resize(e.reader->capacity());
    FrameInfo info;
    const ReadStatus status = e.reader->read(e.frame, info);
    switch (status) {
      case ReadStatus::new_frame:
        e.info = info;
        e.have_frame = true;
        return std::nullopt;
      case ReadStatus::buffer_too_small: continue;  // the region was replaced: resize, retry
      case ReadStatus::region_invalid:
        e.reader.reset();
        return Error{ErrorCode::region_invalid,
                     "the stream's region is no longer valid; its writer may be restarting."};
      default: return std::nullopt;  // nothing newer: keep showing the frame we have
    }
  }
  return std::nullopt;
}

Expected<Picture> PageFrames::image(const std::string& stream) {
  const auto e = entry(stream);
  std::lock_guard lock(e->mutex);
  if (auto error = refresh(*e, stream)) return *error;
  if (!e->have_frame) {
    return Error{ErrorCode::not_found, "the stream has no frame yet."};
  }
  if (e->info.layout.kind != LayoutKind::image) {
    return Error{ErrorCode::invalid_argument, "the stream does not hold images."};
  }
  const std::string key = "image " + std::to_string(e->info.seq);
  if (e->picture.jpeg && e->picture_key == key) return e->picture;
  if (!e->jpeg) {
    auto jpeg = ImageToJpeg::create(quality_);
    if (!jpeg) return jpeg.error();
    e->jpeg.emplace(std::move(jpeg.value()));
  }
  auto out = std::make_shared<std::vector<std::byte>>();
  const auto bytes = std::span<const std::byte>(e->frame.data(), e->info.size);
  if (auto error = e->jpeg->encode(e->info.layout.image, bytes, *out)) return *error;
  const ImageLayout& l = e->info.layout.image;
  e->picture = {out, std::to_string(l.width) + "x" + std::to_string(l.height) + " " +
                         to_string(l.format) + ", frame " + std::to_string(e->info.seq)};
  e->picture_key = key;
  return e->picture;
}

Expected<Picture> PageFrames::top_down(const std::string& stream, const TopDownOptions& options) {
  const auto e = entry(stream);
  std::lock_guard lock(e->mutex);
  if (auto error = refresh(*e, stream)) return *error;
  if (!e->have_frame) {
    return Error{ErrorCode::not_found, "the stream has no frame yet."};
  }
  if (e->info.layout.kind != LayoutKind::points) {
    return Error{ErrorCode::invalid_argument, "the stream does not hold points."};
  }
  const std::string key = "top " + std::to_string(e->info.seq) + " " +
                          std::to_string(static_cast<int>(options.color)) + " " +
                          std::to_string(options.range_m) + " " + std::to_string(options.size_px);
  if (e->picture.jpeg && e->picture_key == key) return e->picture;
  if (!e->jpeg) {
    auto jpeg = ImageToJpeg::create(quality_);
    if (!jpeg) return jpeg.error();
    e->jpeg.emplace(std::move(jpeg.value()));
  }
  TopDownImage raster;
  render_top_down(e->info.layout.points,
                  std::span<const std::byte>(e->frame.data(), e->info.size), options, raster);
  auto out = std::make_shared<std::vector<std::byte>>();
  if (auto error = e->jpeg->encode_rgb(raster.width, raster.height, raster.rgb, *out)) {
    return *error;
  }
  char caption[160];
  std::snprintf(caption, sizeof caption,
                "%llu points, view %.0f m each way, rings every %.0f m, frame %llu",
                static_cast<unsigned long long>(raster.points_drawn), raster.range_m,
                raster.ring_step_m, static_cast<unsigned long long>(e->info.seq));
  e->picture = {out, caption};
  e->picture_key = key;
  return e->picture;
}

}  // namespace sim::foxglove
