// SPDX-License-Identifier: Apache-2.0
// sim_dump: writes frames of a SIM stream to files, one frame file plus a JSON sidecar of its
// metadata per frame: LiDAR streams as PCD (through PCL), image streams as PNG (through OpenCV),
// raw streams as .bin.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "frame_sink.hpp"
#include "sim/apps/camera_info_file.hpp"
#include "sim/apps/command_line.hpp"
#include "sim/apps/status_line.hpp"
#include "sim/apps/stop_signal.hpp"
#include "sim/reader.hpp"

namespace {

// "/lidar_top" → "lidar_top": file names carry the stream name without its slash.
std::string file_stem(const std::string& stream, std::uint64_t seq) {
  char number[32];
  std::snprintf(number, sizeof number, "_%08llu", static_cast<unsigned long long>(seq));
  return stream.substr(stream.find_first_not_of('/')) + number;
}

}  // namespace

int main(int argc, char** argv) {
  std::string stream;
  std::int64_t count = 1;
  std::string out_dir = ".";
  double timeout_s = 5.0;
  bool include_current = false;
  bool quiet = false;
  sim::dump::SinkOptions sink_options;
  sim::apps::CommandLine cli(
      "sim_dump",
      "Writes frames of a SIM stream to files: LiDAR frames as PCD (binary, or --ascii) through "
      "PCL, image frames as PNG, raw streams as .bin, each with a JSON sidecar (seq, stamp_ns, "
      "publish_ns, size, layout). Exit code 1 also when fewer frames than --count arrived.");
  auto& app = cli.app();
  cli.add_stream("stream", stream, "stream name, e.g. /lidar_top (see sim_ls)")->required();
  app.add_option("--count,-n", count, "frames to write; 0 until stopped with Ctrl-C")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--out,-o", out_dir, "folder for the files (created if missing)")
      ->type_name("DIR");
  app.add_flag("--ascii", sink_options.ascii, "PCD in ASCII instead of binary");
  app.add_flag("--xyz", sink_options.xyz_only,
               "PCD with x y z only (pcl::PointXYZ) instead of x y z intensity");
  app.add_flag("--current", include_current,
               "start with the newest frame already published instead of waiting for the next");
  app.add_option("--timeout", timeout_s, "give up when no new frame arrives for this many seconds")
      ->check(CLI::PositiveNumber);
  app.add_flag("-q,--quiet", quiet, "no progress line and no summary");
  sim::ReaderOptions reader_options;
  cli.add_trust(reader_options.trust);
  if (auto code = cli.parse(argc, argv)) return *code;
  const auto& stop = sim::apps::StopSignal::install();

  auto reader = sim::Reader::open(stream, reader_options);
  if (!reader) return cli.fail(std::string_view(reader.error().message));
  auto sink = sim::dump::make_sink(reader->layout(), sink_options);
  if (!sink) return cli.fail(std::string_view(sink.error().message));
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return cli.fail("cannot create the folder " + out_dir + ": " + ec.message());

  std::vector<std::byte> buffer(reader->capacity());
  if (!include_current) {
    // Mark the frame already published as seen, so the dump starts with the next one.
    sim::FrameInfo ignored;
    (void)reader->read(buffer, ignored);
  }
  auto status_line = sim::apps::StatusLine::for_stderr("sim_dump", quiet);
  const auto wanted = static_cast<std::uint64_t>(count);
  const auto timeout = std::chrono::duration<double>(timeout_s);
  std::uint64_t written = 0;
  auto last_frame = std::chrono::steady_clock::now();
  std::uint64_t sensor_generation = 0;
  std::optional<sim::SensorInfo> sensor;
  while ((wanted == 0 || written < wanted) && !stop.requested()) {
    sim::FrameInfo info;
    const sim::ReadStatus status = reader->read_next(buffer, info, std::chrono::milliseconds(100));
    if (status == sim::ReadStatus::buffer_too_small) {
      buffer.resize(reader->capacity());
      continue;
    }
    if (status == sim::ReadStatus::region_invalid) {
      return cli.fail("the stream " + stream + " was removed or damaged while reading; " +
                      std::to_string(written) + " frames were written");
    }
    if (status != sim::ReadStatus::new_frame) {
      if (std::chrono::steady_clock::now() - last_frame > timeout) {
        status_line.finish(std::to_string(written) + " frames written to " + out_dir);
        return cli.fail("no new frame on " + stream + " for " + sim::apps::number(timeout_s) +
                        " s (" + sim::to_string(status) + "); is its writer running?");
      }
      continue;
    }
    last_frame = std::chrono::steady_clock::now();
    const std::string stem = file_stem(stream, info.seq);
    const std::string file_name = stem + (*sink)->extension();
    const std::filesystem::path folder(out_dir);
    if (auto error = (*sink)->write(folder / file_name, std::span(buffer).first(info.size), info)) {
      return cli.fail(std::string_view(error->message));
    }
    // The description, read again only when the writer changed it.
    if (info.sensor_generation != sensor_generation) {
      sensor_generation = info.sensor_generation;
      sensor.reset();
      if (sensor_generation != 0) {
        auto described = reader->sensor_info();
        if (described) {
          sensor = *described;
        } else {
          status_line.note("warning: " + described.error().message);
        }
      }
    }
    // An image's calibration beside it, in the file format it came in (camera_calibration_parsers).
    std::string calibration_file;
    if (sensor && sensor->calibration) {
      calibration_file = stem + ".yaml";
      if (auto saved = sim::apps::save_camera_info(folder / calibration_file, *sensor->calibration);
          !saved) {
        return cli.fail(std::string_view(saved.error().message));
      }
    }
    std::ofstream sidecar(folder / (stem + ".json"));
    sidecar << sim::dump::sidecar_json(stream, info, file_name, sensor, calibration_file);
    if (!sidecar.flush()) return cli.fail("cannot write " + (folder / (stem + ".json")).string());
    ++written;
    status_line.update(sim::apps::fields(
        {{"frames", std::to_string(written) + (wanted != 0 ? "/" + std::to_string(wanted) : "")},
         {"last seq", std::to_string(info.seq)}}));
  }
  status_line.finish(std::to_string(written) + " frames written to " + out_dir);
  return sim::apps::kExitOk;
}
