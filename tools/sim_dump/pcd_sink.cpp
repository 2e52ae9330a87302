// SPDX-License-Identifier: Apache-2.0
// The one translation unit of sim_dump that includes PCL (its headers compile slowly).
#include <pcl/io/pcd_io.h>

#include "frame_sink.hpp"
#include "sim/pcl.hpp"

namespace sim::dump {
namespace {

class PcdSink final : public FrameSink {
 public:
  explicit PcdSink(const SinkOptions& options) : options_(options) {}
  std::string extension() const override { return ".pcd"; }

  std::optional<Error> write(const std::filesystem::path& path, std::span<const std::byte> frame,
                             const FrameInfo& info) override {
    return options_.xyz_only ? save(path, frame, info, xyz_) : save(path, frame, info, xyzi_);
  }

 private:
  template <typename PointT>
  std::optional<Error> save(const std::filesystem::path& path, std::span<const std::byte> frame,
                            const FrameInfo& info, pcl::PointCloud<PointT>& cloud) {
    if (!to_pcl(frame, info, cloud)) {
      return Error{ErrorCode::invalid_argument,
                   "frame " + std::to_string(info.seq) + " is not a whole number of " +
                       info.layout.describe() + " points; nothing was written."};
    }
    pcl::PCDWriter writer;
    // PCL refuses to write an empty cloud; an empty revolution is still a frame worth keeping.
    const int rc = cloud.empty() ? write_empty(path) : writer.write(path.string(), cloud, !options_.ascii);
    if (rc != 0) {
      return Error{ErrorCode::system_error, "cannot write " + path.string() +
                                                "; check that the folder is writable and has space."};
    }
    return std::nullopt;
  }

  int write_empty(const std::filesystem::path& path) const {
    pcl::PointCloud<pcl::PointXYZI> empty;
    const std::string header = pcl::PCDWriter().generateHeader(empty, 0);
    std::FILE* file = std::fopen(path.c_str(), "w");
    if (file == nullptr) return -1;
    const bool ok = std::fputs(header.c_str(), file) >= 0 &&
                    std::fputs(options_.ascii ? "DATA ascii\n" : "DATA binary\n", file) >= 0;
    return std::fclose(file) == 0 && ok ? 0 : -1;
  }

  SinkOptions options_;
  // Kept between frames: the clouds are resized in place, not reallocated per frame.
  pcl::PointCloud<pcl::PointXYZI> xyzi_;
  pcl::PointCloud<pcl::PointXYZ> xyz_;
};

}  // namespace

std::unique_ptr<FrameSink> make_pcd_sink(const SinkOptions& options) {
  return std::make_unique<PcdSink>(options);
}

}  // namespace sim::dump
