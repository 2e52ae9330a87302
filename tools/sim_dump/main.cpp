// SPDX-License-Identifier: Apache-2.0
// sim_dump: writes frames of a SIM stream to files, one frame file plus a JSON sidecar of its
// metadata per frame: LiDAR streams as PCD (through PCL), image streams as PNG (through OpenCV),
// raw streams as .bin.
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "frame_sink.hpp"
#include "sim/reader.hpp"

namespace {

constexpr char tool[] = "sim_dump";
std::atomic<bool> stop_requested{false};
void on_signal(int) { stop_requested.store(true); }

int fail(const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", tool, message.c_str());
  return 1;
}

// "/lidar_top" → "lidar_top": file names carry the stream name without its slash.
std::string file_stem(const std::string& stream, std::uint64_t seq) {
  char number[32];
  std::snprintf(number, sizeof number, "_%08llu", static_cast<unsigned long long>(seq));
  return stream.substr(stream.find_first_not_of('/')) + number;
}

}  // namespace

int main(int argc, char** argv) {
  std::string stream;
  std::uint64_t count = 1;
  std::string out_dir = ".";
  double timeout_s = 5.0;
  bool include_current = false;
  sim::dump::SinkOptions sink_options;
  CLI::App app{
      "Writes frames of a SIM stream to files: LiDAR frames as PCD (binary, or --ascii) through "
      "PCL, raw streams as .bin, each with a JSON sidecar (seq, stamp_ns, publish_ns, size, "
      "layout).\nExit codes: 0 all frames written, 1 failure or too few frames arrived, "
      "2 usage error.",
      tool};
  app.add_option("stream", stream, "stream name, e.g. /lidar_top (see sim_ls)")->required();
  app.add_option("--count,-n", count, "frames to write; 0 until stopped with Ctrl-C [1]");
  app.add_option("--out,-o", out_dir, "folder for the files (created if missing) [.]")
      ->type_name("DIR");
  app.add_flag("--ascii", sink_options.ascii, "PCD in ASCII instead of binary");
  app.add_flag("--xyz", sink_options.xyz_only, "PCD with x y z only (pcl::PointXYZ) instead of x y z intensity");
  app.add_flag("--current", include_current,
               "start with the newest frame already published instead of waiting for the next");
  app.add_option("--timeout", timeout_s, "give up when no new frame arrives for this many seconds [5]")
      ->check(CLI::PositiveNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  auto reader = sim::Reader::open(stream);
  if (!reader) return fail(reader.error().message);
  auto sink = sim::dump::make_sink(reader->layout(), sink_options);
  if (!sink) return fail(sink.error().message);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return fail("cannot create the folder " + out_dir + ": " + ec.message() + ".");

  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  std::vector<std::byte> buffer(reader->capacity());
  if (!include_current) {
    // Mark the frame already published as seen, so the dump starts with the next one.
    sim::FrameInfo ignored;
    (void)reader->read(buffer, ignored);
  }
  const bool terminal = isatty(STDERR_FILENO) != 0;
  const auto timeout = std::chrono::duration<double>(timeout_s);
  std::uint64_t written = 0;
  auto last_frame = std::chrono::steady_clock::now();
  while ((count == 0 || written < count) && !stop_requested.load()) {
    sim::FrameInfo info;
    const sim::ReadStatus status = reader->read_next(buffer, info, std::chrono::milliseconds(100));
    if (status == sim::ReadStatus::region_invalid) {
      return fail("the stream " + stream + " was removed or damaged while reading; " +
                  std::to_string(written) + " frames were written.");
    }
    if (status != sim::ReadStatus::new_frame) {
      if (std::chrono::steady_clock::now() - last_frame > timeout) {
        return fail("no new frame on " + stream + " for " + std::to_string(static_cast<int>(timeout_s)) +
                    " s (" + sim::to_string(status) + "); " + std::to_string(written) +
                    " frames were written. Is its writer running?");
      }
      continue;
    }
    last_frame = std::chrono::steady_clock::now();
    const std::string stem = file_stem(stream, info.seq);
    const std::string file_name = stem + (*sink)->extension();
    const std::filesystem::path folder(out_dir);
    if (auto error = (*sink)->write(folder / file_name, std::span(buffer).first(info.size), info)) {
      return fail(error->message);
    }
    std::ofstream sidecar(folder / (stem + ".json"));
    sidecar << sim::dump::sidecar_json(stream, info, file_name);
    if (!sidecar.flush()) return fail("cannot write " + (folder / (stem + ".json")).string() + ".");
    ++written;
    if (terminal) {
      std::fprintf(stderr, "\r\033[K%llu%s frames written, last seq %llu",
                   static_cast<unsigned long long>(written),
                   count != 0 ? ("/" + std::to_string(count)).c_str() : "",
                   static_cast<unsigned long long>(info.seq));
    }
  }
  if (terminal) std::fprintf(stderr, "\n");
  std::printf("%llu frames written to %s\n", static_cast<unsigned long long>(written), out_dir.c_str());
  return 0;
}
