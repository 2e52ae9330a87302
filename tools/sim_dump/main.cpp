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

struct Options {
  std::string stream;
  std::int64_t count = 1;
  std::string out_dir = ".";
  double timeout_s = 5.0;
  bool include_current = false;
  bool quiet = false;
  sim::dump::SinkOptions sink;
  sim::ReaderOptions reader;
};

void add_options(sim::apps::CommandLine& cli, Options& o) {
  cli.add_stream("stream", o.stream, "stream name, e.g. /lidar_top (see sim_ls)").required();
  cli.add_option("--count,-n", o.count, "frames to write; 0 until stopped with Ctrl-C")
      .non_negative();
  cli.add_option("--out,-o", o.out_dir, "folder for the files (created if missing)")
      .type_name("DIR");
  cli.add_flag("--ascii", o.sink.ascii, "PCD in ASCII instead of binary");
  cli.add_flag("--xyz", o.sink.xyz_only,
               "PCD with x y z only (pcl::PointXYZ) instead of x y z intensity");
  cli.add_flag("--current", o.include_current,
               "start with the newest frame already published instead of waiting for the next");
  cli.add_option("--timeout", o.timeout_s, "give up when no new frame arrives for this many seconds")
      .positive();
  cli.add_flag("-q,--quiet", o.quiet, "no progress line and no summary");
  cli.add_trust(o.reader.trust);
}

// "/lidar_top" → "lidar_top": file names carry the stream name without its slash.
std::string file_stem(const std::string& stream, std::uint64_t seq) {
  char number[32];
  std::snprintf(number, sizeof number, "_%08llu", static_cast<unsigned long long>(seq));
  return stream.substr(stream.find_first_not_of('/')) + number;
}

// The stream's sensor description, read again only when the writer changed it.
class SensorTracker {
 public:
  // The description for a frame of `generation`; one that cannot be read is a warning, and none.
  const std::optional<sim::SensorInfo>& for_frame(const sim::Reader& reader,
                                                  std::uint64_t generation,
                                                  sim::apps::StatusLine& status_line) {
    if (generation == generation_) return sensor_;
    generation_ = generation;
    sensor_.reset();
    if (generation_ != 0) {
      auto described = reader.sensor_info();
      if (described) {
        sensor_ = *described;
      } else {
        status_line.note("warning: " + described.error().message);
      }
    }
    return sensor_;
  }

 private:
  std::uint64_t generation_ = 0;
  std::optional<sim::SensorInfo> sensor_;
};

// What is written beside the frame's file `file_name`: an image's calibration in the file format
// it came in (camera_calibration_parsers), and the JSON sidecar. A sentence when a file cannot be
// written.
std::optional<std::string> write_sidecars(const Options& o, const std::string& stem,
                                          const std::string& file_name, const sim::FrameInfo& info,
                                          const std::optional<sim::SensorInfo>& sensor) {
  const std::filesystem::path folder(o.out_dir);
  std::string calibration_file;
  if (sensor && sensor->calibration) {
    calibration_file = stem + ".yaml";
    if (auto saved = sim::apps::save_camera_info(folder / calibration_file, *sensor->calibration);
        !saved) {
      return saved.error().message;
    }
  }
  std::ofstream sidecar(folder / (stem + ".json"));
  sidecar << sim::dump::sidecar_json(o.stream, info, file_name, sensor, calibration_file);
  if (!sidecar.flush()) return "cannot write " + (folder / (stem + ".json")).string();
  return std::nullopt;
}

// Writes frames until --count of them are written, a stop, or --timeout without a new frame.
int dump_frames(const sim::apps::CommandLine& cli, const Options& o, sim::Reader& reader,
                sim::dump::FrameSink& sink, const sim::apps::StopSignal& stop) {
  std::vector<std::byte> buffer(reader.capacity());
  if (!o.include_current) {
    // Mark the frame already published as seen, so the dump starts with the next one.
    sim::FrameInfo ignored;
    (void)reader.read(buffer, ignored);
  }
  auto status_line = sim::apps::StatusLine::for_stderr("sim_dump", o.quiet);
  const auto wanted = static_cast<std::uint64_t>(o.count);
  const auto timeout = std::chrono::duration<double>(o.timeout_s);
  std::uint64_t written = 0;
  auto last_frame = std::chrono::steady_clock::now();
  SensorTracker sensor;
  while ((wanted == 0 || written < wanted) && !stop.requested()) {
    sim::FrameInfo info;
    const sim::ReadStatus status = reader.read_next(buffer, info, std::chrono::milliseconds(100));
    if (status == sim::ReadStatus::buffer_too_small) {
      buffer.resize(reader.capacity());
      continue;
    }
    if (status == sim::ReadStatus::region_invalid) {
      return cli.fail("the stream " + o.stream + " was removed or damaged while reading; " +
                      std::to_string(written) + " frames were written");
    }
    if (status != sim::ReadStatus::new_frame) {
      if (std::chrono::steady_clock::now() - last_frame > timeout) {
        status_line.finish(std::to_string(written) + " frames written to " + o.out_dir);
        return cli.fail("no new frame on " + o.stream + " for " + sim::apps::number(o.timeout_s) +
                        " s (" + sim::to_string(status) + "); is its writer running?");
      }
      continue;
    }
    last_frame = std::chrono::steady_clock::now();
    const std::string stem = file_stem(o.stream, info.seq);
    const std::string file_name = stem + sink.extension();
    if (auto error = sink.write(std::filesystem::path(o.out_dir) / file_name,
                                std::span(buffer).first(info.size), info)) {
      return cli.fail(std::string_view(error->message));
    }
    const auto& described = sensor.for_frame(reader, info.sensor_generation, status_line);
    if (auto problem = write_sidecars(o, stem, file_name, info, described)) return cli.fail(*problem);
    ++written;
    // append(), not "/" + std::to_string(…): GCC 12 -O3 -Wrestrict false positive (GCC bug 105651).
    status_line.update(sim::apps::fields(
        {{"frames", std::to_string(written) + (wanted != 0 ? std::string("/").append(std::to_string(wanted)) : "")},
         {"last seq", std::to_string(info.seq)}}));
  }
  status_line.finish(std::to_string(written) + " frames written to " + o.out_dir);
  return sim::apps::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  sim::apps::CommandLine cli(
      "sim_dump",
      "Writes frames of a SIM stream to files: LiDAR frames as PCD (binary, or --ascii) through "
      "PCL, image frames as PNG, raw streams as .bin, each with a JSON sidecar (seq, stamp_ns, "
      "publish_ns, size, layout). Exit code 1 also when fewer frames than --count arrived.");
  Options options;
  add_options(cli, options);
  if (auto code = cli.parse(argc, argv)) return *code;
  const auto& stop = sim::apps::StopSignal::install();

  auto reader = sim::Reader::open(options.stream, options.reader);
  if (!reader) return cli.fail(std::string_view(reader.error().message));
  auto sink = sim::dump::make_sink(reader->layout(), options.sink);
  if (!sink) return cli.fail(std::string_view(sink.error().message));
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) return cli.fail("cannot create the folder " + options.out_dir + ": " + ec.message());
  return dump_frames(cli, options, *reader, **sink, stop);
}
