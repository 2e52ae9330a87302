// SPDX-License-Identifier: Apache-2.0
// The GigE Vision / USB3 Vision driver through Aravis 0.8: a buffer pool filled by Aravis's
// stream thread, decoded in its new-buffer callback straight into the writer's slot. Losing the
// camera (control-lost) keeps the stream's region and reopens the camera by the same id.
// Aravis (GLib) stays in the one translation unit behind this header.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sim/camera/camera_clock.hpp"
#include "sim/imaging/image_format.hpp"
#include "sim/layout.hpp"
#include "sim/result.hpp"
#include "sim/sensor_info.hpp"

namespace sim::camera {

struct AravisCaptureConfig {
  std::string device_id;      // Aravis id, serial number or IP address; empty: the first camera
  std::string stream = "/camera_front";
  std::string pixel_format;   // GenICam name (Mono8, BayerRG8, RGB8, …); empty: keep the camera's
  imaging::OutputFormat output = imaging::OutputFormat::bgr8;
  double fps = 0;             // 0: keep
  double exposure_us = 0;     // 0: keep
  double gain = -1;           // negative: keep
  std::int32_t offset_x = 0;  // region of interest; width/height 0 keep the camera's
  std::int32_t offset_y = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t packet_size = 0;  // GigE packet size; 0: Aravis negotiates
  bool packet_socket = true;     // AF_PACKET receive (needs CAP_NET_RAW); off: plain UDP socket
  std::vector<std::pair<std::string, std::string>> features;  // any GenICam feature, as text
  std::uint32_t buffers = 8;
  // The camera's clock instead of the host receive time; automatic when the camera reports PTP
  // on (PtpEnable or GevIEEE1588).
  bool device_timestamps = false;
  bool checksum = false;
  // The stream's description (frame, mounting, calibration); the capture adds the device info
  // (vendor, model, serial, firmware) and the clock of the stamps with the PTP state, on every
  // (re)connect. Calibration size as in V4l2CaptureConfig. nullopt: no description.
  std::optional<SensorInfo> sensor;
  std::chrono::milliseconds retry_period{1000};
  std::function<void(std::string_view)> log;
  // The clock check: each frame's stamp against its arrival (Aravis's host stamp of its first
  // packet), judged with the reported clock (reported_clock()) and the host's (`host_clock`;
  // empty: unknown) and written to the stream's clock record about once a second.
  timing::ClockTolerance clock_tolerance = camera_clock_tolerance();
  std::function<ClockStatus()> host_clock;
};

struct AravisStats {
  std::uint64_t published = 0;
  std::uint64_t incomplete = 0;       // buffers Aravis could not complete (missing packets, …)
  std::uint64_t dropped = 0;          // gaps in the camera's frame ids
  std::uint64_t bad_size = 0;         // buffers of another size or pixel format
  std::uint64_t missing_packets = 0;  // GigE Vision stream statistics
  std::uint64_t resent_packets = 0;
  std::uint64_t control_losses = 0;
  std::uint64_t reconnects = 0;
};

// The GenICam pixel format name's SIM format, or unknown.
PixelFormat pixel_format_of_genicam(std::string_view name) noexcept;

class AravisCapture {
 public:
  // Opens the camera, applies the settings, creates the stream and starts acquisition.
  static Expected<AravisCapture> start(AravisCaptureConfig config);

  AravisCapture(AravisCapture&&) noexcept;
  AravisCapture& operator=(AravisCapture&&) noexcept;
  AravisCapture(const AravisCapture&) = delete;
  AravisCapture& operator=(const AravisCapture&) = delete;
  ~AravisCapture();

  // Watches the camera until `stop`: after control-lost it reopens it every retry_period.
  // `on_tick` (optional) runs about ten times a second, e.g. for a status line.
  void run(const std::atomic<bool>& stop, const std::function<void(const AravisCapture&)>& on_tick = {});

  AravisStats stats() const noexcept;
  const ImageLayout& output_layout() const noexcept;
  std::string camera_name() const;
  bool connected() const noexcept;
  // The clock of the stream's stamps and the camera's PTP state (genicam_clock_status), read
  // from the camera on connect and about once a second by run(), off the frame path; readable
  // from any thread: hand it to the clock reporter.
  ReportedClock reported_clock() const;

  // Ids of the cameras Aravis discovers ("Aravis-Fake-GV01 (127.0.0.1)", …).
  static std::vector<std::string> list_cameras();

  struct Impl;

 private:
  explicit AravisCapture(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::camera
