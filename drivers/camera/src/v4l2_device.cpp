// SPDX-License-Identifier: Apache-2.0
#include "sim/camera/v4l2_device.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <utility>

namespace sim::camera {

namespace {

constexpr FourCc kYuyv = FourCc::of('Y', 'U', 'Y', 'V');
constexpr FourCc kUyvy = FourCc::of('U', 'Y', 'V', 'Y');
constexpr FourCc kMjpg = FourCc::of('M', 'J', 'P', 'G');
constexpr FourCc kJpeg = FourCc::of('J', 'P', 'E', 'G');
constexpr FourCc kGrey = FourCc::of('G', 'R', 'E', 'Y');
constexpr FourCc kY16 = FourCc::of('Y', '1', '6', ' ');
constexpr FourCc kRgb3 = FourCc::of('R', 'G', 'B', '3');
constexpr FourCc kBgr3 = FourCc::of('B', 'G', 'R', '3');
constexpr FourCc kRggb = FourCc::of('R', 'G', 'G', 'B');
constexpr FourCc kBa81 = FourCc::of('B', 'A', '8', '1');  // BGGR
constexpr FourCc kGbrg = FourCc::of('G', 'B', 'R', 'G');
constexpr FourCc kGrbg = FourCc::of('G', 'R', 'B', 'G');

std::string errno_text(int error) { return std::strerror(error); }

bool lost(int error) { return error == ENODEV || error == EIO || error == ENXIO; }

std::string c_string(const unsigned char* text, std::size_t capacity) {
  const auto* begin = reinterpret_cast<const char*>(text);
  return {begin, strnlen(begin, capacity)};
}

double fps_of(const v4l2_fract& time_per_frame) {
  if (time_per_frame.numerator == 0) return 0;
  return static_cast<double>(time_per_frame.denominator) / time_per_frame.numerator;
}

}  // namespace

std::optional<FourCc> FourCc::parse(std::string_view text) noexcept {
  if (text == "MJPEG") text = "MJPG";
  if (text.size() < 1 || text.size() > 4) return std::nullopt;
  char c[4] = {' ', ' ', ' ', ' '};
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (!std::isprint(static_cast<unsigned char>(text[i]))) return std::nullopt;
    c[i] = text[i];
  }
  return of(c[0], c[1], c[2], c[3]);
}

std::string FourCc::str() const {
  std::string text;
  for (int shift = 0; shift < 32; shift += 8) {
    const auto c = static_cast<char>((code >> shift) & 0xff);
    text.push_back(std::isprint(static_cast<unsigned char>(c)) ? c : '?');
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

PixelFormat pixel_format_of(FourCc fourcc) noexcept {
  if (fourcc == kYuyv) return PixelFormat::yuyv;
  if (fourcc == kUyvy) return PixelFormat::uyvy;
  if (fourcc == kMjpg || fourcc == kJpeg) return PixelFormat::mjpeg;
  if (fourcc == kGrey) return PixelFormat::mono8;
  if (fourcc == kY16) return PixelFormat::mono16;
  if (fourcc == kRgb3) return PixelFormat::rgb8;
  if (fourcc == kBgr3) return PixelFormat::bgr8;
  if (fourcc == kRggb) return PixelFormat::bayer_rggb8;
  if (fourcc == kBa81) return PixelFormat::bayer_bggr8;
  if (fourcc == kGbrg) return PixelFormat::bayer_gbrg8;
  if (fourcc == kGrbg) return PixelFormat::bayer_grbg8;
  return PixelFormat::unknown;
}

std::string control_key(std::string_view name) {
  std::string key;
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u)) {
      key.push_back(static_cast<char>(std::tolower(u)));
    } else if (!key.empty() && key.back() != '_') {
      key.push_back('_');
    }
  }
  while (!key.empty() && key.back() == '_') key.pop_back();
  return key;
}

Expected<V4l2Device> V4l2Device::open(V4l2Io& io, const std::string& path) {
  const int fd = io.open(path.c_str(), O_RDWR | O_NONBLOCK);
  if (fd < 0) {
    const int error = errno;
    if (error == ENOENT) {
      return Error{ErrorCode::not_found,
                   "no video device at " + path +
                       ": check the camera is plugged in and the path (ls /dev/video* "
                       "/dev/v4l/by-id/); this kernel may have no V4L2 support at all"};
    }
    if (error == EACCES) {
      return Error{ErrorCode::permission_denied,
                   "no permission to open " + path + ": add the user to the 'video' group"};
    }
    return Error{ErrorCode::system_error, "cannot open " + path + ": " + errno_text(error)};
  }
  V4l2Device device(io, fd, path, {});
  v4l2_capability caps{};
  if (device.xioctl(VIDIOC_QUERYCAP, &caps) < 0) {
    return Error{ErrorCode::invalid_argument,
                 path + " is not a V4L2 device (" + errno_text(errno) + "): pass a /dev/videoN node"};
  }
  const std::uint32_t device_caps =
      (caps.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? caps.device_caps : caps.capabilities;
  if ((device_caps & V4L2_CAP_VIDEO_CAPTURE) == 0) {
    return Error{ErrorCode::invalid_argument,
                 path + " cannot capture video (it may be the camera's metadata node): try the "
                        "other /dev/videoN of this camera"};
  }
  if ((device_caps & V4L2_CAP_STREAMING) == 0) {
    return Error{ErrorCode::invalid_argument,
                 path + " does not support streaming I/O, which this driver needs"};
  }
  device.card_ = c_string(caps.card, sizeof caps.card);
  device.bus_ = c_string(caps.bus_info, sizeof caps.bus_info);
  return device;
}

V4l2Device::V4l2Device(V4l2Io& io, int fd, std::string path, std::string card) noexcept
    : io_(&io), fd_(fd), path_(std::move(path)), card_(std::move(card)) {}

V4l2Device::V4l2Device(V4l2Device&& other) noexcept
    : io_(other.io_),
      fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      card_(std::move(other.card_)),
      bus_(std::move(other.bus_)),
      buffers_(std::move(other.buffers_)),
      buffers_requested_(std::exchange(other.buffers_requested_, false)),
      streaming_(std::exchange(other.streaming_, false)) {
  other.buffers_.clear();
}

V4l2Device& V4l2Device::operator=(V4l2Device&& other) noexcept {
  if (this != &other) {
    close();
    io_ = other.io_;
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    card_ = std::move(other.card_);
    bus_ = std::move(other.bus_);
    buffers_ = std::move(other.buffers_);
    other.buffers_.clear();
    buffers_requested_ = std::exchange(other.buffers_requested_, false);
    streaming_ = std::exchange(other.streaming_, false);
  }
  return *this;
}

V4l2Device::~V4l2Device() { close(); }

void V4l2Device::close() noexcept {
  if (fd_ < 0) return;
  stop();
  io_->close(fd_);
  fd_ = -1;
}

int V4l2Device::xioctl(unsigned long request, void* arg) {
  int rc = 0;
  do {
    rc = io_->ioctl(fd_, request, arg);
  } while (rc < 0 && errno == EINTR);
  return rc;
}

std::vector<double> V4l2Device::frame_rates(std::uint32_t fourcc, std::uint32_t width,
                                            std::uint32_t height) {
  std::vector<double> rates;
  for (std::uint32_t index = 0; index < 64; ++index) {
    v4l2_frmivalenum interval{};
    interval.index = index;
    interval.pixel_format = fourcc;
    interval.width = width;
    interval.height = height;
    if (xioctl(VIDIOC_ENUM_FRAMEINTERVALS, &interval) < 0) break;
    if (interval.type == V4L2_FRMIVAL_TYPE_DISCRETE) {
      rates.push_back(fps_of(interval.discrete));
    } else {
      // Continuous or stepwise: the fastest and slowest rates bound what S_PARM accepts.
      rates.push_back(fps_of(interval.stepwise.min));
      rates.push_back(fps_of(interval.stepwise.max));
      break;
    }
  }
  return rates;
}

std::vector<FrameSizeInfo> V4l2Device::frame_sizes(std::uint32_t fourcc) {
  std::vector<FrameSizeInfo> sizes;
  for (std::uint32_t index = 0; index < 256; ++index) {
    v4l2_frmsizeenum size{};
    size.index = index;
    size.pixel_format = fourcc;
    if (xioctl(VIDIOC_ENUM_FRAMESIZES, &size) < 0) break;
    if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
      sizes.push_back({size.discrete.width, size.discrete.height,
                       frame_rates(fourcc, size.discrete.width, size.discrete.height)});
    } else {
      const auto& s = size.stepwise;
      sizes.push_back({s.min_width, s.min_height, frame_rates(fourcc, s.min_width, s.min_height)});
      sizes.push_back({s.max_width, s.max_height, frame_rates(fourcc, s.max_width, s.max_height)});
      break;
    }
  }
  return sizes;
}

std::vector<FormatInfo> V4l2Device::formats() {
  std::vector<FormatInfo> result;
  for (std::uint32_t index = 0; index < 64; ++index) {
    v4l2_fmtdesc desc{};
    desc.index = index;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &desc) < 0) break;
    FormatInfo info;
    info.fourcc = FourCc{desc.pixelformat};
    info.description = c_string(desc.description, sizeof desc.description);
    info.compressed = (desc.flags & V4L2_FMT_FLAG_COMPRESSED) != 0;
    info.sizes = frame_sizes(desc.pixelformat);
    result.push_back(std::move(info));
  }
  return result;
}

std::vector<ControlInfo> V4l2Device::controls() {
  std::vector<ControlInfo> result;
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (xioctl(VIDIOC_QUERYCTRL, &query) == 0) {
    const std::uint32_t id = query.id;
    if ((query.flags & V4L2_CTRL_FLAG_DISABLED) == 0 && query.type != V4L2_CTRL_TYPE_CTRL_CLASS) {
      ControlInfo info;
      info.id = id;
      info.name = c_string(query.name, sizeof query.name);
      info.key = control_key(info.name);
      info.type = query.type;
      info.minimum = query.minimum;
      info.maximum = query.maximum;
      info.step = query.step;
      info.default_value = query.default_value;
      info.read_only = (query.flags & V4L2_CTRL_FLAG_READ_ONLY) != 0;
      v4l2_control control{};
      control.id = id;
      if ((query.flags & V4L2_CTRL_FLAG_WRITE_ONLY) == 0 && xioctl(VIDIOC_G_CTRL, &control) == 0) {
        info.value = control.value;
      }
      if (query.type == V4L2_CTRL_TYPE_MENU && query.minimum >= 0 && query.maximum < 256) {
        for (std::int32_t i = query.minimum; i <= query.maximum; ++i) {
          v4l2_querymenu menu{};
          menu.id = id;
          menu.index = static_cast<std::uint32_t>(i);
          if (xioctl(VIDIOC_QUERYMENU, &menu) == 0) {
            info.menu.emplace_back(i, c_string(menu.name, sizeof menu.name));
          }
        }
      }
      result.push_back(std::move(info));
    }
    query = {};
    query.id = id | V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  return result;
}

std::optional<Error> V4l2Device::set_control(std::string_view key, std::string_view value) {
  const std::string wanted = control_key(key);
  const auto all = controls();
  const auto it = std::find_if(all.begin(), all.end(),
                               [&](const ControlInfo& c) { return c.key == wanted; });
  if (it == all.end()) {
    return Error{ErrorCode::invalid_argument,
                 "the camera has no control '" + std::string(key) +
                     "': list them with --list-controls"};
  }
  std::int32_t number = 0;
  bool parsed = false;
  if (it->type == V4L2_CTRL_TYPE_BOOLEAN && (value == "true" || value == "false")) {
    number = value == "true" ? 1 : 0;
    parsed = true;
  }
  if (!parsed) {
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), number);
    parsed = ec == std::errc{} && end == value.data() + value.size();
  }
  if (!parsed) {
    for (const auto& [index, name] : it->menu) {
      if (control_key(name) == control_key(value)) {
        number = index;
        parsed = true;
      }
    }
  }
  if (!parsed) {
    return Error{ErrorCode::invalid_argument,
                 // Not `"'" + std::string(value)`: GCC 12 at -O3 warns (-Wrestrict, GCC bug
                 // 105651) inside operator+(const char*, string&&); append() says the same.
                 std::string("'").append(value) + "' is not a value for control " + it->key +
                     ": give a number (or true/false, or a menu entry)"};
  }
  if (it->read_only) {
    return Error{ErrorCode::invalid_argument, "control " + it->key + " is read-only"};
  }
  if (number < it->minimum || number > it->maximum) {
    return Error{ErrorCode::invalid_argument,
                 "control " + it->key + " takes " + std::to_string(it->minimum) + " to " +
                     std::to_string(it->maximum) + ", not " + std::string(value)};
  }
  v4l2_control control{};
  control.id = it->id;
  control.value = number;
  if (xioctl(VIDIOC_S_CTRL, &control) < 0) {
    return Error{ErrorCode::system_error,
                 "the camera refused " + it->key + "=" + std::string(value) + ": " +
                     errno_text(errno)};
  }
  return std::nullopt;
}

namespace {

const FormatInfo* find_format(const std::vector<FormatInfo>& offered, FourCc fourcc) {
  const auto it = std::find_if(offered.begin(), offered.end(),
                               [&](const FormatInfo& f) { return f.fourcc == fourcc; });
  return it == offered.end() ? nullptr : &*it;
}

// --format FOURCC: offered by the device and decodable.
Expected<FourCc> requested_format(const std::vector<FormatInfo>& offered, FourCc fourcc,
                                  const std::string& path) {
  if (find_format(offered, fourcc) == nullptr) {
    return Error{ErrorCode::invalid_argument,
                 path + " does not offer format " + fourcc.str() +
                     ": see --list-formats, or use --format auto"};
  }
  if (pixel_format_of(fourcc) == PixelFormat::unknown) {
    return Error{ErrorCode::invalid_argument,
                 "format " + fourcc.str() + " cannot be decoded: use --format auto"};
  }
  return fourcc;
}

// Whether the device offers `fourcc`, at width × height when `need_size`, and at the request's
// rate or faster when `need_rate` (a size without listed rates offers any).
bool offers(const std::vector<FormatInfo>& offered, FourCc fourcc, std::uint32_t width,
            std::uint32_t height, double fps, bool need_size, bool need_rate) {
  const FormatInfo* format = find_format(offered, fourcc);
  if (format == nullptr) return false;
  if (!need_size) return true;
  for (const auto& size : format->sizes) {
    if (size.width != width || size.height != height) continue;
    if (!need_rate || size.fps.empty()) return true;
    for (const double offered_fps : size.fps) {
      if (offered_fps + 0.01 >= fps) return true;
    }
  }
  return false;
}

// --format auto: uncompressed first (cheapest to decode), MJPEG when it is the only way to reach
// the requested size and rate (USB 2 cameras give YUYV at full size only at low rates).
Expected<FourCc> preferred_format(const std::vector<FormatInfo>& offered,
                                  const FormatRequest& request, std::uint32_t width,
                                  std::uint32_t height, const std::string& path) {
  std::vector<FourCc> preference = {kYuyv, kUyvy, kMjpg, kJpeg, kGrey, kY16, kBgr3, kRgb3,
                                    kRggb, kBa81, kGbrg, kGrbg};
  if (request.output == imaging::OutputFormat::mono8) {
    preference.insert(preference.begin(), {kGrey, kY16});
  }
  for (const auto& [need_size, need_rate] :
       {std::pair{true, request.fps > 0}, std::pair{true, false}, std::pair{false, false}}) {
    for (const FourCc candidate : preference) {
      if (offers(offered, candidate, width, height, request.fps, need_size, need_rate)) {
        return candidate;
      }
    }
  }
  return Error{ErrorCode::invalid_argument,
               path + " offers no format SIM can decode: see --list-formats"};
}

// What is wrong with the format the device settled on, if anything: another pixel format than
// asked for, or sizes no frame can have.
std::optional<Error> settled_format_problem(const v4l2_pix_format& pix, FourCc chosen,
                                            const std::string& path) {
  if (pix.pixelformat != chosen.code) {
    return Error{ErrorCode::invalid_argument,
                 path + " switched the format to " + FourCc{pix.pixelformat}.str() +
                     " instead of " + chosen.str() + ": choose another --format"};
  }
  const PixelFormat pixel = pixel_format_of(chosen);
  const std::uint64_t row = imaging::row_bytes(pix.width, pixel);
  if (pix.width == 0 || pix.height == 0 || (!imaging::is_compressed(pixel) && pix.bytesperline < row) ||
      (!imaging::is_compressed(pixel) && pix.sizeimage < std::uint64_t{pix.bytesperline} * pix.height)) {
    return Error{ErrorCode::invalid_argument,
                 path + " reported an impossible format (" + std::to_string(pix.width) + "x" +
                     std::to_string(pix.height) + ", " + std::to_string(pix.bytesperline) +
                     " bytes per line): the camera driver is broken"};
  }
  return std::nullopt;
}

}  // namespace

Expected<StreamFormat> V4l2Device::negotiate(const FormatRequest& request) {
  v4l2_format current{};
  current.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_FMT, &current) < 0) {
    return Error{ErrorCode::system_error,
                 "cannot read the format of " + path_ + ": " + errno_text(errno)};
  }
  const std::uint32_t width = request.width != 0 ? request.width : current.fmt.pix.width;
  const std::uint32_t height = request.height != 0 ? request.height : current.fmt.pix.height;
  const auto offered = formats();
  auto choice = request.fourcc ? requested_format(offered, *request.fourcc, path_)
                               : preferred_format(offered, request, width, height, path_);
  if (!choice) return choice.error();
  const FourCc chosen = *choice;

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = width;
  format.fmt.pix.height = height;
  format.fmt.pix.pixelformat = chosen.code;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(VIDIOC_S_FMT, &format) < 0) {
    return Error{ErrorCode::system_error, path_ + " refused format " + chosen.str() + " " +
                                              std::to_string(width) + "x" +
                                              std::to_string(height) + ": " + errno_text(errno)};
  }
  const auto& pix = format.fmt.pix;
  if (auto problem = settled_format_problem(pix, chosen, path_)) return *problem;
  StreamFormat result;
  result.fourcc = chosen;
  result.layout =
      imaging::make_layout(pix.width, pix.height, pixel_format_of(chosen), pix.bytesperline);
  result.size_image = pix.sizeimage;

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_G_PARM, &parm) == 0) {
    if (request.fps > 0 && (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0) {
      parm.parm.capture.timeperframe.numerator = 1000;
      parm.parm.capture.timeperframe.denominator =
          static_cast<std::uint32_t>(std::lround(request.fps * 1000));
      xioctl(VIDIOC_S_PARM, &parm);  // the device answers with the rate it picked
    }
    result.fps = fps_of(parm.parm.capture.timeperframe);
  }
  return result;
}

std::optional<Error> V4l2Device::start(std::uint32_t buffer_count) {
  stop();
  v4l2_requestbuffers request{};
  request.count = buffer_count;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (xioctl(VIDIOC_REQBUFS, &request) < 0) {
    return Error{ErrorCode::system_error,
                 path_ + " cannot allocate capture buffers: " + errno_text(errno)};
  }
  buffers_requested_ = true;
  if (request.count < 2) {
    stop();
    return Error{ErrorCode::system_error, path_ + " gave fewer than two capture buffers"};
  }
  for (std::uint32_t index = 0; index < request.count; ++index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    if (xioctl(VIDIOC_QUERYBUF, &buffer) < 0) {
      const int error = errno;
      stop();
      return Error{ErrorCode::system_error, path_ + " cannot describe buffer " +
                                                std::to_string(index) + ": " + errno_text(error)};
    }
    void* address = io_->mmap(buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_,
                              buffer.m.offset);
    if (address == MAP_FAILED) {
      const int error = errno;
      stop();
      return Error{ErrorCode::system_error,
                   path_ + " cannot map a capture buffer: " + errno_text(error)};
    }
    buffers_.push_back({address, buffer.length});
    if (xioctl(VIDIOC_QBUF, &buffer) < 0) {
      const int error = errno;
      stop();
      return Error{ErrorCode::system_error,
                   path_ + " cannot queue a capture buffer: " + errno_text(error)};
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_STREAMON, &type) < 0) {
    const int error = errno;
    stop();
    return Error{ErrorCode::system_error, path_ + " cannot start streaming: " + errno_text(error)};
  }
  streaming_ = true;
  return std::nullopt;
}

const char* to_string(BufferClock clock) noexcept {
  switch (clock) {
    case BufferClock::unknown: return "unknown";
    case BufferClock::monotonic: return "monotonic";
    case BufferClock::copy: return "copy";
  }
  return "unknown";
}

BufferClock buffer_clock(std::uint32_t flags) noexcept {
  switch (flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) {  // a value field, not bits
    case V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC: return BufferClock::monotonic;
    case V4L2_BUF_FLAG_TIMESTAMP_COPY: return BufferClock::copy;
    default: return BufferClock::unknown;
  }
}

StampPoint stamp_point(std::uint32_t flags) noexcept {
  return (flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE ? StampPoint::start_of_exposure
                                                                                : StampPoint::end_of_frame;
}

WaitResult V4l2Device::wait(int timeout_ms, DeviceFrame& frame) {
  pollfd fds{fd_, POLLIN, 0};
  const int ready = io_->poll(&fds, 1, timeout_ms);
  if (ready < 0) return errno == EINTR ? WaitResult::again : WaitResult::device_lost;
  if (ready == 0) return WaitResult::timeout;
  if ((fds.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) return WaitResult::device_lost;

  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  if (io_->ioctl(fd_, VIDIOC_DQBUF, &buffer) < 0) {
    const int error = errno;
    if (error == EAGAIN || error == EINTR) return WaitResult::again;
    return WaitResult::device_lost;
  }
  if (buffer.index >= buffers_.size()) return WaitResult::device_lost;  // a broken driver
  const Buffer& mapped = buffers_[buffer.index];
  frame.index = buffer.index;
  frame.bytes = {static_cast<const std::byte*>(mapped.address),
                 std::min<std::size_t>(buffer.bytesused, mapped.length)};
  frame.sequence = buffer.sequence;
  frame.timestamp_ns = std::int64_t{buffer.timestamp.tv_sec} * 1'000'000'000 +
                       std::int64_t{buffer.timestamp.tv_usec} * 1'000;
  frame.clock = buffer_clock(buffer.flags);
  frame.stamp_point = stamp_point(buffer.flags);
  frame.error = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0;
  return WaitResult::frame;
}

WaitResult V4l2Device::requeue(const DeviceFrame& frame) {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = frame.index;
  if (xioctl(VIDIOC_QBUF, &buffer) < 0) return lost(errno) ? WaitResult::device_lost
                                                           : WaitResult::again;
  return WaitResult::frame;
}

void V4l2Device::stop() noexcept {
  if (fd_ < 0) return;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (const Buffer& buffer : buffers_) io_->munmap(buffer.address, buffer.length);
  buffers_.clear();
  if (buffers_requested_) {
    buffers_requested_ = false;
    v4l2_requestbuffers request{};
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    xioctl(VIDIOC_REQBUFS, &request);  // count 0 frees them; fails harmlessly on a lost device
  }
}

}  // namespace sim::camera
