// SPDX-License-Identifier: Apache-2.0
#include "page_frames.hpp"

#include <cstdio>

namespace sim::foxglove {
namespace {

void test_hook() {
  if (testing::before_picture != nullptr) testing::before_picture();
}

}  // namespace

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

std::optional<Error> PageFrames::newest(Entry& e, const std::string& stream,
                                         LayoutKind kind) const {
  if (auto error = refresh(e, stream)) return error;
  if (!e.have_frame) return Error{ErrorCode::not_found, stream + " has no frame yet."};
  if (e.info.layout.kind != kind) {
    return Error{ErrorCode::invalid_argument,
                 stream + (kind == LayoutKind::image ? " does not hold images."
                                                     : " does not hold points.")};
  }
  return std::nullopt;
}

Expected<Picture> PageFrames::image(const std::string& stream) {
  test_hook();
  const auto e = entry(stream);
  std::lock_guard lock(e->mutex);
  if (auto error = newest(*e, stream, LayoutKind::image)) return *error;
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
  test_hook();
  const auto e = entry(stream);
  std::lock_guard lock(e->mutex);
  if (auto error = newest(*e, stream, LayoutKind::points)) return *error;
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
  // The colour scale in words (blue → red), since the picture has no legend of its own.
  char caption[240];
  const bool by_height = options.color == ColorBy::height || e->info.layout.points.type == PointType::xyz32;
  std::snprintf(caption, sizeof caption,
                "%llu points, view %.0f m each way, rings every %.0f m, frame %llu; colour: %s "
                "%.1f%s (blue) to %.1f%s (red)",
                static_cast<unsigned long long>(raster.points_drawn), raster.range_m,
                raster.ring_step_m, static_cast<unsigned long long>(e->info.seq),
                by_height ? "height" : "intensity", raster.colour_low, by_height ? " m" : "",
                raster.colour_high, by_height ? " m" : "");
  e->picture = {out, caption};
  e->picture_key = key;
  return e->picture;
}

Expected<Picture> PageFrames::projection(const std::string& camera, const std::string& lidar,
                                         const Pose& lidar_to_camera,
                                         const CameraCalibration& calibration) {
  test_hook();
  const auto c = entry(camera);
  const auto l = entry(lidar);
  std::scoped_lock lock(c->mutex, l->mutex);  // both, in an order that cannot deadlock
  if (auto error = newest(*c, camera, LayoutKind::image)) return *error;
  if (auto error = newest(*l, lidar, LayoutKind::points)) return *error;
  const std::string key = "projection " + std::to_string(c->info.seq) + " " + std::to_string(l->info.seq) +
                          " " + lidar;
  const bool same_pose = c->picture_pose.rotation == lidar_to_camera.rotation &&
                         c->picture_pose.translation == lidar_to_camera.translation;
  if (c->picture.jpeg && c->picture_key == key && same_pose && c->picture_calibration == calibration) {
    return c->picture;
  }
  if (!c->jpeg) {
    auto jpeg = ImageToJpeg::create(quality_);
    if (!jpeg) return jpeg.error();
    c->jpeg.emplace(std::move(jpeg.value()));
  }
  const ImageLayout& image = c->info.layout.image;
  if (auto error = c->jpeg->to_bgr(image, std::span(c->frame.data(), c->info.size), c->bgr)) {
    return *error;
  }
  const ProjectionResult drawn = draw_projected_points(
      l->info.layout.points, std::span<const std::byte>(l->frame.data(), l->info.size),
      lidar_to_camera, calibration, image.width, image.height, c->bgr);
  auto out = std::make_shared<std::vector<std::byte>>();
  if (auto error = c->jpeg->encode_bgr(image.width, image.height, c->bgr, *out)) return *error;
  char caption[320];
  std::snprintf(caption, sizeof caption,
                "%llu of %llu points of %s in the picture (frames %llu and %llu); colour: "
                "distance from the camera %.1f m (blue) to %.1f m (red)",
                static_cast<unsigned long long>(drawn.projected),
                static_cast<unsigned long long>(drawn.points), lidar.c_str(),
                static_cast<unsigned long long>(c->info.seq),
                static_cast<unsigned long long>(l->info.seq), drawn.nearest_m, drawn.farthest_m);
  c->picture = {out, caption};
  c->picture_key = key;
  c->picture_pose = lidar_to_camera;
  c->picture_calibration = calibration;
  return c->picture;
}

}  // namespace sim::foxglove
