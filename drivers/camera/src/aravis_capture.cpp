// SPDX-License-Identifier: Apache-2.0
#include "sim/camera/aravis_capture.hpp"

#include <arv.h>

#include <optional>
#include <thread>

#include "sim/apps/camera_info_file.hpp"
#include "sim/imaging/decoder.hpp"
#include "sim/clock.hpp"
#include "sim/timing/clock_reporter.hpp"
#include "sim/writer.hpp"

namespace sim::camera {

namespace {

std::string take_message(GError*& error, const std::string& fallback) {
  std::string text = error != nullptr && error->message != nullptr ? error->message : fallback;
  g_clear_error(&error);
  return text;
}

PixelFormat pixel_format_of_arv(ArvPixelFormat format) noexcept {
  switch (format) {
    case ARV_PIXEL_FORMAT_MONO_8: return PixelFormat::mono8;
    case ARV_PIXEL_FORMAT_MONO_16: return PixelFormat::mono16;
    case ARV_PIXEL_FORMAT_RGB_8_PACKED: return PixelFormat::rgb8;
    case ARV_PIXEL_FORMAT_BGR_8_PACKED: return PixelFormat::bgr8;
    case ARV_PIXEL_FORMAT_BAYER_RG_8: return PixelFormat::bayer_rggb8;
    case ARV_PIXEL_FORMAT_BAYER_BG_8: return PixelFormat::bayer_bggr8;
    case ARV_PIXEL_FORMAT_BAYER_GB_8: return PixelFormat::bayer_gbrg8;
    case ARV_PIXEL_FORMAT_BAYER_GR_8: return PixelFormat::bayer_grbg8;
    case ARV_PIXEL_FORMAT_YUV_422_YUYV_PACKED: return PixelFormat::yuyv;
    case ARV_PIXEL_FORMAT_YUV_422_PACKED: return PixelFormat::uyvy;  // GigE Vision order: U Y V Y
    default: return PixelFormat::unknown;
  }
}

}  // namespace

PixelFormat pixel_format_of_genicam(std::string_view name) noexcept {
  struct Entry {
    std::string_view name;
    PixelFormat format;
  };
  static constexpr Entry table[] = {
      {"Mono8", PixelFormat::mono8},         {"Mono16", PixelFormat::mono16},
      {"RGB8", PixelFormat::rgb8},           {"RGB8Packed", PixelFormat::rgb8},
      {"BGR8", PixelFormat::bgr8},           {"BGR8Packed", PixelFormat::bgr8},
      {"BayerRG8", PixelFormat::bayer_rggb8}, {"BayerBG8", PixelFormat::bayer_bggr8},
      {"BayerGB8", PixelFormat::bayer_gbrg8}, {"BayerGR8", PixelFormat::bayer_grbg8},
      {"YUV422_8", PixelFormat::yuyv},       {"YUV422Packed", PixelFormat::uyvy},
      {"YUV422_8_UYVY", PixelFormat::uyvy},
  };
  for (const auto& entry : table) {
    if (entry.name == name) return entry.format;
  }
  return PixelFormat::unknown;
}

struct AravisCapture::Impl {
  AravisCaptureConfig config;
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  gulong control_lost_handler = 0;
  std::optional<imaging::FrameDecoder> decoder;
  std::optional<Writer> writer;
  std::optional<SensorInfo> sensor;  // the description the stream carries
  ImageLayout input{};
  std::string name;
  std::atomic<bool> lost{false};
  bool device_time = false;  // stamp with the camera's clock: asked for, or PTP is on
  ReportedClock reported;    // the camera's clock as last read (main thread), for any reader
  std::optional<timing::ClockReporter> clock_check;  // fed and ticked by the stream thread only
  std::chrono::steady_clock::time_point clock_read{};  // when it was read
  std::optional<std::uint64_t> last_frame_id;  // touched by the stream thread only
  std::atomic<std::uint64_t> published{0};
  std::atomic<std::uint64_t> incomplete{0};
  std::atomic<std::uint64_t> dropped{0};
  std::atomic<std::uint64_t> bad_size{0};
  std::uint64_t missing_packets = 0;  // accumulated over sessions (main thread)
  std::uint64_t resent_packets = 0;
  std::uint64_t control_losses = 0;
  std::uint64_t reconnects = 0;

  ~Impl() { disconnect(); }

  void log(const std::string& message) const {
    if (config.log) config.log(message);
  }

  // Emitted by Aravis's heartbeat thread: only flag it; the main loop reconnects.
  static void on_control_lost(ArvDevice*, gpointer data) {
    static_cast<Impl*>(data)->lost.store(true);
  }

  // Emitted by Aravis's stream thread for every completed (or failed) buffer.
  static void on_new_buffer(ArvStream* stream, gpointer data) {
    auto* self = static_cast<Impl*>(data);
    ArvBuffer* buffer = arv_stream_try_pop_buffer(stream);
    if (buffer == nullptr) return;
    self->handle(buffer);
    arv_stream_push_buffer(stream, buffer);
  }

  void handle(ArvBuffer* buffer) {
    if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS) {
      incomplete.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    // GigE Vision 1 frame ids are 16-bit and skip 0 when they wrap.
    const std::uint64_t id = arv_buffer_get_frame_id(buffer);
    if (last_frame_id) {
      if (id > *last_frame_id + 1) {
        dropped.fetch_add(id - *last_frame_id - 1, std::memory_order_relaxed);
      } else if (id < *last_frame_id && *last_frame_id - id > 32768 && *last_frame_id <= 65535) {
        dropped.fetch_add(65535 - *last_frame_id + id - 1, std::memory_order_relaxed);
      }
    }
    last_frame_id = id;

    if (pixel_format_of_arv(arv_buffer_get_image_pixel_format(buffer)) != input.format ||
        static_cast<std::uint32_t>(arv_buffer_get_image_width(buffer)) != input.width ||
        static_cast<std::uint32_t>(arv_buffer_get_image_height(buffer)) != input.height) {
      bad_size.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    std::size_t size = 0;
    const void* data = arv_buffer_get_data(buffer, &size);
    // Aravis stamps each buffer with the host's realtime clock when its first packet arrived.
    const auto received = static_cast<std::int64_t>(arv_buffer_get_system_timestamp(buffer));
    const std::int64_t stamp =
        device_time ? static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer)) : received;
    clock_check->start(*writer);  // the stream's first record, before its first frame: once
    Loan loan = writer->loan();
    const imaging::DecodeResult decoded =
        decoder->decode({static_cast<const std::byte*>(data), size}, loan.bytes());
    if (decoded.status != imaging::DecodeStatus::ok) {
      bad_size.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    const std::int64_t published_stamp = stamp > 0 ? stamp : realtime_ns();
    if (std::move(loan).commit(decoded.size, published_stamp, received) == WriteStatus::ok) {
      published.fetch_add(1, std::memory_order_relaxed);
      clock_check->add(published_stamp, received);  // what readers get against the frame's arrival
      clock_check->tick(*writer, received);
    }
  }

  std::optional<Error> fail(const std::string& message) {
    disconnect();
    return Error{ErrorCode::system_error, message};
  }

  // A feature's value as text (strings, enumerations, numbers), or "" when the camera has none.
  static std::string feature_text(ArvDevice* device, const char* feature) {
    ArvGcNode* node = arv_device_get_feature(device, feature);
    if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) return {};
    GError* error = nullptr;
    const char* value = arv_gc_feature_node_get_value_as_string(ARV_GC_FEATURE_NODE(node), &error);
    g_clear_error(&error);
    return value != nullptr ? sensor_text(value, SensorInfo::kMaxName) : std::string();
  }

  static std::string first_feature(ArvDevice* device, std::initializer_list<const char*> names) {
    for (const char* name : names) {
      if (std::string value = feature_text(device, name); !value.empty()) return value;
    }
    return {};
  }

  // The first of `names` the camera has as an integer, or nullopt.
  static std::optional<std::int64_t> integer_feature(ArvDevice* device, std::initializer_list<const char*> names) {
    for (const char* name : names) {
      if (arv_device_get_feature(device, name) == nullptr) continue;
      GError* error = nullptr;
      const gint64 value = arv_device_get_integer_feature_value(device, name, &error);
      if (error == nullptr) return value;
      g_clear_error(&error);
    }
    return std::nullopt;
  }

  // The camera's PTP features, as far as it has them (SFNC names first, then GigE Vision's).
  static PtpReading read_ptp(ArvDevice* device) {
    PtpReading ptp;
    for (const char* name : {"PtpEnable", "GevIEEE1588"}) {
      if (arv_device_get_feature(device, name) == nullptr) continue;
      GError* error = nullptr;
      ptp.has_ptp = true;
      ptp.enabled = arv_device_get_boolean_feature_value(device, name, &error) != FALSE && error == nullptr;
      g_clear_error(&error);
      break;
    }
    if (!ptp.enabled) return ptp;
    // The latch makes status, offset and grandmaster one moment's values (SFNC: the Ptp* reads
    // show the latched data set).
    for (const char* latch : {"PtpDataSetLatch", "GevIEEE1588DataSetLatch"}) {
      if (arv_device_get_feature(device, latch) == nullptr) continue;
      GError* error = nullptr;
      arv_device_execute_command(device, latch, &error);
      g_clear_error(&error);
      break;
    }
    ptp.status = first_feature(device, {"PtpStatus", "GevIEEE1588StatusLatched", "GevIEEE1588Status"});
    ptp.servo = first_feature(device, {"PtpServoStatus"});
    ptp.offset_from_master_ns = integer_feature(device, {"PtpOffsetFromMaster", "GevIEEE1588OffsetFromMaster"});
    if (const auto id = integer_feature(device, {"PtpGrandmasterClockID"})) {
      ptp.grandmaster = static_cast<std::uint64_t>(*id);
    }
    return ptp;
  }

  // Reads the camera's clock into `reported` (the control channel: main thread, off the frame path).
  void report_clock(ArvDevice* device) {
    const ClockStatus clock = genicam_clock_status(read_ptp(device), device_time, realtime_ns());
    // Said once when it changes, not every second.
    if (!clock.problem.empty() && clock.problem != reported().problem) log("warning: " + clock.problem);
    reported.set(clock);
    clock_read = std::chrono::steady_clock::now();
  }

  // config.sensor completed with the device info and the clock of the stamps; the calibration's
  // size checked against the frames (an error on the first connect, dropped with a log line
  // after a reconnect in another size).
  Expected<std::optional<SensorInfo>> describe(ArvDevice* device, bool first) const {
    if (!config.sensor) return std::optional<SensorInfo>();
    SensorInfo info = *config.sensor;
    const ImageLayout& output = decoder->output_layout();
    if (info.calibration) {
      if (auto fits = apps::check_calibration_size(*info.calibration, output.width, output.height);
          !fits) {
        if (first) return fits.error();
        log("warning: " + fits.error().message + "; the stream carries no calibration now");
        info.calibration.reset();
      }
    }
    info.identity.vendor = first_feature(device, {"DeviceVendorName"});
    info.identity.model = first_feature(device, {"DeviceModelName"});
    info.identity.serial = first_feature(device, {"DeviceSerialNumber", "DeviceID"});
    info.identity.firmware = first_feature(device, {"DeviceFirmwareVersion", "DeviceVersion"});
    info.point_time = PointTime::none;
    const std::string ptp_enabled = first_feature(device, {"PtpEnable", "GevIEEE1588"});
    const bool ptp = ptp_enabled == "true" || ptp_enabled == "1";
    const std::string ptp_status = first_feature(device, {"PtpStatus", "GevIEEE1588Status"});
    if (!device_time) {
      info.time_base = TimeBase::host;
      info.time_sync = ptp ? "host receive time (PTP " + (ptp_status.empty() ? "on" : ptp_status) + ")"
                           : "host receive time";
    } else if (ptp) {
      // Slave: locked to a master; Master: the camera is the network's clock.
      const bool locked = ptp_status == "Slave" || ptp_status == "Master";
      info.time_base = locked ? TimeBase::sensor_synchronized : TimeBase::sensor_free_running;
      info.time_sync = "PTP " + (ptp_status.empty() ? std::string("on, state not reported") : ptp_status);
    } else {
      info.time_base = TimeBase::sensor_free_running;
      info.time_sync = "the camera's clock, PTP off";
    }
    return std::optional<SensorInfo>(std::move(info));
  }

  // Connects to the camera, configures it, makes (or keeps) the stream and starts acquisition;
  // on the first connect also creates the writer. Every failure disconnects.
  std::optional<Error> connect() {
    const bool first = !writer.has_value();
    if (auto e = open_camera()) return e;
    if (auto e = configure()) return e;
    ArvDevice* device = arv_camera_get_device(camera);
    if (auto e = apply_features(device)) return e;
    device_time = uses_device_time(device);
    report_clock(device);
    if (auto e = create_decoder()) return e;
    if (auto e = prepare_writer(device, first)) return e;
    clock_check->restart();  // a camera back after a loss is a new measurement, not a step
    return start_acquisition(device);
  }

  // The failure "the camera refused <what>: <why>" when `error` is set (and clears it).
  std::optional<Error> refused(GError*& error, const std::string& what) {
    if (error == nullptr) return std::nullopt;
    return fail("the camera refused " + what + ": " + take_message(error, "unknown error"));
  }

  std::optional<Error> open_camera() {
    GError* error = nullptr;
    camera = arv_camera_new(config.device_id.empty() ? nullptr : config.device_id.c_str(), &error);
    if (camera == nullptr) {
      const std::string why = take_message(error, "not found");
      return Error{ErrorCode::not_found,
                   "no camera " + (config.device_id.empty() ? std::string("at all")
                                                            : "'" + config.device_id + "'") +
                       " (" + why + "): check the id with --list, the cable and the subnet"};
    }
    const char* model = arv_camera_get_model_name(camera, nullptr);
    const char* vendor = arv_camera_get_vendor_name(camera, nullptr);
    name = std::string(vendor != nullptr ? vendor : "?") + " " + (model != nullptr ? model : "?");
    return std::nullopt;
  }

  // The pixel format, region, frame rate, exposure and gain the options ask for.
  std::optional<Error> configure() {
    GError* error = nullptr;
    if (!config.pixel_format.empty()) {
      if (pixel_format_of_genicam(config.pixel_format) == PixelFormat::unknown) {
        return fail("pixel format " + config.pixel_format +
                    " cannot be decoded: use Mono8, Mono16, RGB8, BGR8, Bayer??8 or YUV422_8");
      }
      arv_camera_set_pixel_format_from_string(camera, config.pixel_format.c_str(), &error);
      if (auto e = refused(error, "pixel format " + config.pixel_format)) return e;
    }
    if (config.width > 0 && config.height > 0) {
      arv_camera_set_region(camera, config.offset_x, config.offset_y, config.width, config.height,
                            &error);
      if (auto e = refused(error, "the region of interest")) return e;
    }
    if (config.fps > 0) {
      arv_camera_set_frame_rate(camera, config.fps, &error);
      if (auto e = refused(error, "the frame rate")) return e;
    }
    if (config.exposure_us > 0) {
      arv_camera_set_exposure_time(camera, config.exposure_us, &error);
      if (auto e = refused(error, "the exposure time")) return e;
    }
    if (config.gain >= 0) {
      arv_camera_set_gain(camera, config.gain, &error);
      if (auto e = refused(error, "the gain")) return e;
    }
    return std::nullopt;
  }

  // The GenICam features given by name, and GigE Vision's packet size and socket.
  std::optional<Error> apply_features(ArvDevice* device) {
    GError* error = nullptr;
    for (const auto& [feature, value] : config.features) {
      ArvGcNode* node = arv_device_get_feature(device, feature.c_str());
      if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) {
        return fail("the camera has no GenICam feature '" + feature + "'");
      }
      arv_gc_feature_node_set_value_from_string(ARV_GC_FEATURE_NODE(node), value.c_str(), &error);
      if (auto e = refused(error, feature + "=" + value)) return e;
    }
    if (arv_camera_is_gv_device(camera)) {
      if (config.packet_size > 0) {
        arv_camera_gv_set_packet_size(camera, config.packet_size, &error);
        if (auto e = refused(error, "packet size " + std::to_string(config.packet_size))) return e;
      }
      if (!config.packet_socket) {
        arv_camera_gv_set_stream_options(camera, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
      }
    }
    return std::nullopt;
  }

  // A camera synchronised by PTP has a clock worth using; otherwise the host receive time is the
  // better stamp (free-running camera clocks start at power-up).
  bool uses_device_time(ArvDevice* device) const {
    bool use = config.device_timestamps;
    for (const char* ptp : {"PtpEnable", "GevIEEE1588"}) {
      if (use || arv_device_get_feature(device, ptp) == nullptr) continue;
      GError* ignored = nullptr;
      use = arv_device_get_boolean_feature_value(device, ptp, &ignored) != FALSE;
      g_clear_error(&ignored);
    }
    return use;
  }

  // The decoder for the region and pixel format the camera now sends.
  std::optional<Error> create_decoder() {
    GError* error = nullptr;
    gint x = 0;
    gint y = 0;
    gint width = 0;
    gint height = 0;
    arv_camera_get_region(camera, &x, &y, &width, &height, &error);
    if (auto e = refused(error, "reading its region")) return e;
    const ArvPixelFormat arv_format = arv_camera_get_pixel_format(camera, &error);
    if (auto e = refused(error, "reading its pixel format")) return e;
    const PixelFormat format = pixel_format_of_arv(arv_format);
    if (format == PixelFormat::unknown) {
      return fail("the camera's pixel format cannot be decoded: choose one with --pixel-format");
    }
    input = imaging::make_layout(static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height),
                        format);
    auto created = imaging::FrameDecoder::create(input, config.output);
    if (!created) return fail(created.error().message);
    decoder.emplace(std::move(created.value()));
    return std::nullopt;
  }

  // The writer of the decoder's frames: made on the first connect, made again when a reconnected
  // camera sends another layout, else kept, with the description updated when it changed.
  std::optional<Error> prepare_writer(ArvDevice* device, bool first) {
    auto described = describe(device, first);
    if (!described) {
      disconnect();
      return described.error();
    }
    const Layout layout = Layout::of(decoder->output_layout());
    const std::uint64_t capacity = decoder->output_capacity(0);
    if (!writer || writer->layout() != layout || writer->capacity() != capacity) {
      writer.reset();  // release the writer lock before the region is replaced
      StreamSpec spec;
      spec.name = config.stream;
      spec.layout = layout;
      spec.capacity = capacity;
      spec.checksum = config.checksum;
      spec.sensor = *described;
      auto made = Writer::create(spec);
      if (!made) {
        disconnect();
        return made.error();
      }
      writer.emplace(std::move(made.value()));
      clock_check->new_stream();  // its first frame carries the clock record too
    } else if (*described && *described != sensor) {
      // The same stream after a reconnect: readers see what changed (the PTP state, a camera).
      if (auto set = writer->set_sensor_info(**described); !set) log("warning: " + set.error().message);
    }
    sensor = *described;
    return std::nullopt;
  }

  // Opens the camera's stream with its buffers, hooks the signals and starts acquisition.
  std::optional<Error> start_acquisition(ArvDevice* device) {
    GError* error = nullptr;
    const guint payload = arv_camera_get_payload(camera, &error);
    if (auto e = refused(error, "reading its payload size")) return e;
    stream = arv_camera_create_stream(camera, nullptr, nullptr, &error);
    if (stream == nullptr) {
      return fail("cannot open the camera's stream: " + take_message(error, "unknown error"));
    }
    for (std::uint32_t i = 0; i < config.buffers; ++i) {
      arv_stream_push_buffer(stream, arv_buffer_new_allocate(payload));
    }
    last_frame_id.reset();
    lost.store(false);
    control_lost_handler =
        g_signal_connect(device, "control-lost", G_CALLBACK(&Impl::on_control_lost), this);
    g_signal_connect(stream, "new-buffer", G_CALLBACK(&Impl::on_new_buffer), this);
    arv_stream_set_emit_signals(stream, TRUE);
    arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    if (auto e = refused(error, "continuous acquisition")) return e;
    arv_camera_start_acquisition(camera, &error);
    if (auto e = refused(error, "starting acquisition")) return e;
    return std::nullopt;
  }

  // Drops the camera and its stream (joining Aravis's stream thread); the writer stays.
  void disconnect() noexcept {
    if (stream != nullptr) {
      arv_stream_set_emit_signals(stream, FALSE);
      if (ARV_IS_GV_STREAM(stream)) {
        guint64 resent = 0;
        guint64 missing = 0;
        arv_gv_stream_get_statistics(ARV_GV_STREAM(stream), &resent, &missing);
        resent_packets += resent;
        missing_packets += missing;
      }
    }
    if (camera != nullptr && !lost.load()) arv_camera_stop_acquisition(camera, nullptr);
    if (camera != nullptr && control_lost_handler != 0) {
      g_signal_handler_disconnect(arv_camera_get_device(camera), control_lost_handler);
    }
    control_lost_handler = 0;
    g_clear_object(&stream);
    g_clear_object(&camera);
  }
};

Expected<AravisCapture> AravisCapture::start(AravisCaptureConfig config) {
  if (config.buffers < 2 || config.buffers > 64) {
    return Error{ErrorCode::invalid_argument, "--buffers must be 2 to 64"};
  }
  auto impl = std::make_unique<Impl>();
  impl->config = std::move(config);
  impl->clock_check.emplace(impl->config.clock_tolerance);
  impl->clock_check->set_sources({impl->reported, impl->config.host_clock});
  if (auto error = impl->connect()) return *error;
  return AravisCapture(std::move(impl));
}

AravisCapture::AravisCapture(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
AravisCapture::AravisCapture(AravisCapture&&) noexcept = default;
AravisCapture& AravisCapture::operator=(AravisCapture&&) noexcept = default;
AravisCapture::~AravisCapture() = default;

void AravisCapture::run(const std::atomic<bool>& stop,
                        const std::function<void(const AravisCapture&)>& on_tick) {
  using Clock = std::chrono::steady_clock;
  Impl& s = *impl_;
  auto next_retry = Clock::now();
  while (!stop.load()) {
    if (s.camera != nullptr && s.lost.load()) {
      ++s.control_losses;
      s.log("lost control of the camera; the stream stays and the camera is retried");
      s.disconnect();
      next_retry = Clock::now();
    }
    if (s.camera != nullptr && !s.lost.load() && Clock::now() - s.clock_read >= std::chrono::seconds(1)) {
      s.report_clock(arv_camera_get_device(s.camera));  // about once a second, off the frame path
    }
    if (s.camera == nullptr && Clock::now() >= next_retry) {
      if (auto error = s.connect()) {
        next_retry = Clock::now() + s.config.retry_period;
      } else {
        ++s.reconnects;
        s.log("reconnected to " + s.name + "; streaming again");
      }
    }
    if (on_tick) on_tick(*this);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

AravisStats AravisCapture::stats() const noexcept {
  const Impl& s = *impl_;
  AravisStats stats;
  stats.published = s.published.load();
  stats.incomplete = s.incomplete.load();
  stats.dropped = s.dropped.load();
  stats.bad_size = s.bad_size.load();
  stats.missing_packets = s.missing_packets;
  stats.resent_packets = s.resent_packets;
  stats.control_losses = s.control_losses;
  stats.reconnects = s.reconnects;
  return stats;
}

const ImageLayout& AravisCapture::output_layout() const noexcept {
  return impl_->decoder->output_layout();
}
std::string AravisCapture::camera_name() const { return impl_->name; }
bool AravisCapture::connected() const noexcept { return impl_->camera != nullptr; }
ReportedClock AravisCapture::reported_clock() const { return impl_->reported; }

std::vector<std::string> AravisCapture::list_cameras() {
  arv_update_device_list();
  std::vector<std::string> ids;
  for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
    const char* id = arv_get_device_id(i);
    const char* address = arv_get_device_address(i);
    ids.push_back(std::string(id != nullptr ? id : "?") + " (" + (address != nullptr ? address : "?") +
                  ")");
  }
  return ids;
}

}  // namespace sim::camera
