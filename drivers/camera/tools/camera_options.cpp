// SPDX-License-Identifier: Apache-2.0
#include "camera_options.hpp"

#include "sim/apps/host_clock_options.hpp"
#include "sim/imaging/image_format.hpp"

namespace sim::camera {
namespace {

// "name=value" items (--ctrl, --feature, or a YAML map) into pairs; the offending item otherwise.
std::optional<std::string> split_pairs(const std::vector<std::string>& items, const char* option,
                                       std::vector<std::pair<std::string, std::string>>& out) {
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      return std::string(option) + " '" + item + "' must be name=value";
    }
    out.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return std::nullopt;
}

// The sensor options into the capture's description; the problem's sentence otherwise.
std::optional<std::string> describe(const apps::SensorOptions& options, const std::string& stream,
                                    std::optional<SensorInfo>& sensor) {
  auto info = apps::sensor_info_from(options, stream);
  if (!info) return info.error().message;
  sensor = std::move(info.value());
  return std::nullopt;
}

void add_clock_options(apps::CommandLine& cli, ClockToleranceOptions& o) {
  cli.add_option("--clock-offset-ok-ms", o.offset_ok_ms,
                 "how far a frame's stamp may lie from its arrival before the clock check warns: the "
                 "exposure, readout and transfer time")
      .in_range(0.0, 999.0);
  cli.add_option("--clock-spread-warn-ms", o.spread_warn_ms,
                 "how much that may vary from frame to frame before the clock check warns")
      .in_range(0.0, 999.0);
  apps::add_host_clock_options(cli, o.host);
}

// The tolerance options into nanoseconds; the problem's sentence otherwise.
std::optional<std::string> finish_clock_options(ClockToleranceOptions& o) {
  o.tolerance = camera_clock_tolerance();
  o.tolerance.offset_ok_ns = static_cast<std::int64_t>(o.offset_ok_ms * 1e6);
  o.tolerance.spread_warn_ns = static_cast<std::int64_t>(o.spread_warn_ms * 1e6);
  if (o.tolerance.offset_ok_ns >= o.tolerance.offset_error_ns) {
    return "--clock-offset-ok-ms must be below 1000: a stamp a second from its arrival cannot be paired";
  }
  return std::nullopt;
}

}  // namespace

void add_v4l2_options(apps::CommandLine& cli, V4l2Options& o) {
  cli.add_config_file();
  cli.add_option("device", o.config.device, "video device node");
  cli.add_stream("--stream", o.config.stream, "SIM stream name");
  cli.add_option("--format", o.format, "device format: auto, YUYV, UYVY, MJPG, GREY, Y16, ...");
  cli.add_option("--width", o.config.format.width, "frame width (0: the device's current one)");
  cli.add_option("--height", o.config.format.height, "frame height (0: the device's current one)");
  cli.add_option("--fps", o.config.format.fps, "frame rate to request (0: the device's current one)")
      .in_range(0.0, 1000.0);
  cli.add_option("--output", o.output, "published format: bgr8, rgb8, mono8 or raw")
      .one_of({"bgr8", "rgb8", "mono8", "raw"});
  cli.add_option("--ctrl,--controls", o.controls,
                 "V4L2 control as name=value, repeatable (see --list-controls)");
  cli.add_option("--buffers", o.config.buffers, "number of mmap buffers").in_range(2, 32);
  cli.add_option("--timestamps", o.timestamps, "frame stamps: device or receive")
      .one_of({"device", "receive"});
  cli.add_option("--time-offset-ns", o.config.time_offset_ns, "added to every frame stamp");
  cli.add_option("--frame-timeout-ms", o.frame_timeout_ms,
                 "restart the stream after this long without a frame");
  cli.add_option("--retry-period-ms", o.retry_period_ms,
                 "between attempts to reopen a lost device");
  cli.add_flag("--checksum", o.config.checksum, "publish an XXH3 checksum with every frame");
  add_clock_options(cli, o.clock);
  cli.add_flag("--list-formats", o.list_formats, "list the device's formats, sizes and rates");
  cli.add_flag("--list-controls", o.list_controls, "list the device's controls");
  apps::add_sensor_options(cli, o.sensor, apps::SensorKind::camera);
  cli.add_placement(o.placement);
  cli.add_flag("-q,--quiet", o.quiet, "no status line and no summary");
}

std::optional<std::string> finish_v4l2_options(V4l2Options& o) {
  if (o.format == "auto") {
    o.config.format.fourcc.reset();
  } else if (auto fourcc = FourCc::parse(o.format)) {
    o.config.format.fourcc = fourcc;
  } else {
    return "--format '" + o.format + "' is not auto or a four-letter code like YUYV";
  }
  o.config.format.output = *imaging::parse_output_format(o.output);
  o.config.timestamps =
      o.timestamps == "device" ? TimestampSource::device : TimestampSource::receive;
  o.config.frame_timeout = std::chrono::milliseconds(o.frame_timeout_ms);
  o.config.retry_period = std::chrono::milliseconds(o.retry_period_ms);
  std::vector<std::pair<std::string, std::string>> pairs;
  if (auto problem = split_pairs(o.controls, "--ctrl", pairs)) return problem;
  o.config.controls.clear();
  for (auto& [key, value] : pairs) o.config.controls.push_back({key, value});
  if (auto problem = finish_clock_options(o.clock)) return problem;
  o.config.clock_tolerance = o.clock.tolerance;
  return describe(o.sensor, o.config.stream, o.config.sensor);
}

void add_aravis_options(apps::CommandLine& cli, AravisOptions& o) {
  cli.add_config_file();
  cli.add_option("device", o.config.device_id,
                 "camera id, serial number or IP (empty: the first camera)");
  cli.add_stream("--stream", o.config.stream, "SIM stream name");
  cli.add_option("--pixel-format", o.config.pixel_format,
                 "GenICam pixel format (Mono8, BayerRG8, ...; empty: the camera's)");
  cli.add_option("--output", o.output, "published format: bgr8, rgb8, mono8 or raw")
      .one_of({"bgr8", "rgb8", "mono8", "raw"});
  cli.add_option("--fps", o.config.fps, "acquisition frame rate (0: the camera's)")
      .in_range(0.0, 10000.0);
  cli.add_option("--exposure,--exposure-us", o.config.exposure_us,
                 "exposure time in microseconds (0: the camera's)")
      .non_negative();
  cli.add_option("--gain", o.config.gain, "gain in camera units (negative: the camera's)");
  cli.add_option("--roi", o.roi, "region of interest: X Y WIDTH HEIGHT").expected(4);
  cli.add_option("--packet-size", o.config.packet_size,
                 "GigE packet size in bytes (0: Aravis negotiates)")
      .in_range(0, 16000);
  cli.add_flag("--packet-socket,!--no-packet-socket", o.config.packet_socket,
               "receive through AF_PACKET (needs CAP_NET_RAW); --no-packet-socket: a plain UDP "
               "socket that drops more");
  cli.add_option("--feature,--features", o.features,
                 "any GenICam feature as Name=value, repeatable, applied in order");
  cli.add_option("--buffers", o.config.buffers, "buffers in the pool").in_range(2, 64);
  cli.add_flag("--device-timestamps", o.config.device_timestamps,
               "stamp frames with the camera's clock (enable PTP on the camera)");
  cli.add_option("--retry-period-ms", o.retry_period_ms, "between attempts to find a lost camera");
  add_clock_options(cli, o.clock);
  cli.add_flag("--checksum", o.config.checksum, "publish an XXH3 checksum with every frame");
  cli.add_flag("--list", o.list, "list the cameras Aravis finds and exit");
  apps::add_sensor_options(cli, o.sensor, apps::SensorKind::camera);
  cli.add_placement(o.placement);
  cli.add_flag("-q,--quiet", o.quiet, "no status line and no summary");
}

std::optional<std::string> finish_aravis_options(AravisOptions& o) {
  o.config.output = *imaging::parse_output_format(o.output);
  if (o.roi.size() == 4) {
    o.config.offset_x = o.roi[0];
    o.config.offset_y = o.roi[1];
    o.config.width = o.roi[2];
    o.config.height = o.roi[3];
  } else if (!o.roi.empty()) {
    return "--roi takes four numbers: X Y WIDTH HEIGHT";
  }
  o.config.retry_period = std::chrono::milliseconds(o.retry_period_ms);
  o.config.features.clear();
  if (auto problem = split_pairs(o.features, "--feature", o.config.features)) return problem;
  if (auto problem = finish_clock_options(o.clock)) return problem;
  o.config.clock_tolerance = o.clock.tolerance;
  return describe(o.sensor, o.config.stream, o.config.sensor);
}

}  // namespace sim::camera
