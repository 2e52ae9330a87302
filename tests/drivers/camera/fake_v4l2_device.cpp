// SPDX-License-Identifier: Apache-2.0
#include "fake_v4l2_device.hpp"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "sim/imaging/image_format.hpp"
#include "sim/clock.hpp"

namespace sim::camera::testing {

namespace {

constexpr std::int64_t kOffsetStride = std::int64_t{1} << 26;  // mmap offset of buffer i: i × this

void copy_name(unsigned char* out, std::size_t capacity, const std::string& name) {
  std::memset(out, 0, capacity);
  std::memcpy(out, name.data(), std::min(name.size(), capacity - 1));
}

}  // namespace

FakeV4l2Device::FakeV4l2Device(std::string path, std::vector<FakeFormat> formats,
                               std::vector<FakeControl> controls)
    : path_(std::move(path)), formats_(std::move(formats)), controls_(std::move(controls)) {
  if (!formats_.empty() && !formats_.front().sizes.empty()) {
    pixelformat_ = formats_.front().fourcc.code;
    width_ = formats_.front().sizes.front().first;
    height_ = formats_.front().sizes.front().second;
  }
}

FakeV4l2Device::~FakeV4l2Device() = default;

void FakeV4l2Device::push_frame(FakeFrame frame) { events_.emplace_back(std::move(frame)); }
void FakeV4l2Device::push_error(int error) { events_.emplace_back(error); }
void FakeV4l2Device::push_stall() { events_.emplace_back(Stall{}); }

void FakeV4l2Device::unplug() {
  unplugged_ = true;
  streaming_ = false;
  queue_.clear();
  // Open handles are dead from now on: they stay open until the driver closes them.
  std::set<int> dead;
  for (const int fd : fds_) dead.insert(-fd);
  fds_ = dead;
}

void FakeV4l2Device::plug() { unplugged_ = false; }

std::uint32_t FakeV4l2Device::bytes_per_line() const {
  const PixelFormat pixel = pixel_format_of(FourCc{pixelformat_});
  if (imaging::is_compressed(pixel)) return 0;
  return static_cast<std::uint32_t>(imaging::row_bytes(width_, pixel)) + row_padding_;
}

std::uint32_t FakeV4l2Device::size_image() const {
  if (imaging::is_compressed(pixel_format_of(FourCc{pixelformat_}))) return width_ * height_ * 2;
  return bytes_per_line() * height_;
}

std::int32_t FakeV4l2Device::control(std::uint32_t id) const {
  for (const auto& c : controls_) {
    if (c.id == id) return c.value;
  }
  return -1;
}

const FakeFormat* FakeV4l2Device::find(std::uint32_t fourcc) const {
  for (const auto& f : formats_) {
    if (f.fourcc.code == fourcc) return &f;
  }
  return nullptr;
}

int FakeV4l2Device::fail(int error) const {
  errno = error;
  return -1;
}

void FakeV4l2Device::free_buffers() {
  for (auto& buffer : buffers_) retired_.push_back(std::move(buffer.memory));
  buffers_.clear();
  queue_.clear();
}

int FakeV4l2Device::open(const char* path, int) {
  if (unplugged_ || path_ != path) return fail(ENOENT);
  ++opens_;
  const int fd = next_fd_++;
  fds_.insert(fd);
  return fd;
}

int FakeV4l2Device::close(int fd) {
  if (fds_.erase(fd) == 0 && fds_.erase(-fd) == 0) return fail(EBADF);
  if (fds_.empty() || unplugged_) {
    streaming_ = false;
    if (mapped_ == 0) free_buffers();
  }
  return 0;
}

void* FakeV4l2Device::mmap(std::size_t length, int, int, int fd, std::int64_t offset) {
  if (fds_.count(fd) == 0) {
    errno = unplugged_ || fds_.count(-fd) != 0 ? ENODEV : EBADF;
    return MAP_FAILED;
  }
  const auto index = static_cast<std::size_t>(offset / kOffsetStride);
  if (offset % kOffsetStride != 0 || index >= buffers_.size() ||
      length > buffers_[index].length) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++mapped_;
  return buffers_[index].memory.get();
}

int FakeV4l2Device::munmap(void*, std::size_t) {
  if (mapped_ == 0) return fail(EINVAL);
  --mapped_;
  if (mapped_ == 0 && fds_.empty()) free_buffers();
  return 0;
}

int FakeV4l2Device::poll(pollfd* fds, nfds_t count, int) {
  if (count != 1) return fail(EINVAL);
  pollfd& p = fds[0];
  p.revents = 0;
  if (fds_.count(p.fd) == 0 || unplugged_ || !streaming_) {
    p.revents = POLLERR;  // what V4L2 reports for a gone device or a stopped stream
    return 1;
  }
  if (events_.empty()) return 0;  // no frame: a timeout, returned at once to keep tests fast
  if (std::holds_alternative<Stall>(events_.front())) {
    events_.pop_front();
    return 0;
  }
  if (std::holds_alternative<FakeFrame>(events_.front()) && queue_.empty()) return 0;
  p.revents = POLLIN | POLLRDNORM;
  return 1;
}

int FakeV4l2Device::dequeue(void* arg) {
  auto* buffer = static_cast<v4l2_buffer*>(arg);
  if (!streaming_) return fail(EINVAL);
  if (events_.empty()) return fail(EAGAIN);
  if (const int* error = std::get_if<int>(&events_.front())) {
    const int e = *error;
    events_.pop_front();
    if (e == ENODEV) unplug();
    return fail(e);
  }
  if (std::holds_alternative<Stall>(events_.front()) || queue_.empty()) return fail(EAGAIN);
  FakeFrame frame = std::move(std::get<FakeFrame>(events_.front()));
  events_.pop_front();
  const std::uint32_t index = queue_.front();
  queue_.pop_front();
  Buffer& target = buffers_[index];
  target.queued = false;
  const std::size_t used = std::min(frame.bytes.size(), target.length);
  if (used > 0) std::memcpy(target.memory.get(), frame.bytes.data(), used);
  sequence_ += frame.sequence_gap;
  const std::int64_t stamp = frame.timestamp_ns >= 0 ? frame.timestamp_ns : monotonic_ns();
  *buffer = {};
  buffer->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer->memory = V4L2_MEMORY_MMAP;
  buffer->index = index;
  buffer->bytesused = static_cast<std::uint32_t>(used);
  buffer->length = static_cast<std::uint32_t>(target.length);
  buffer->sequence = sequence_++;
  buffer->timestamp.tv_sec = stamp / 1'000'000'000;
  buffer->timestamp.tv_usec = (stamp % 1'000'000'000) / 1'000;
  buffer->flags = frame.timestamp_flags | (frame.error_flag ? V4L2_BUF_FLAG_ERROR : 0u);
  return 0;
}

int FakeV4l2Device::ioctl(int fd, unsigned long request, void* arg) {
  if (fds_.count(fd) == 0) return fail(fds_.count(-fd) != 0 ? ENODEV : EBADF);
  switch (request) {
    case VIDIOC_QUERYCAP: return query_capabilities(arg);
    case VIDIOC_ENUM_FMT: return enumerate_format(arg);
    case VIDIOC_ENUM_FRAMESIZES: return enumerate_frame_size(arg);
    case VIDIOC_ENUM_FRAMEINTERVALS: return enumerate_frame_interval(arg);
    case VIDIOC_G_FMT: return get_format(arg);
    case VIDIOC_TRY_FMT: return try_or_set_format(arg, false);
    case VIDIOC_S_FMT: return try_or_set_format(arg, true);
    case VIDIOC_G_PARM: return stream_parameters(arg, false);
    case VIDIOC_S_PARM: return stream_parameters(arg, true);
    case VIDIOC_QUERYCTRL: return query_control(arg);
    case VIDIOC_QUERYMENU: return query_menu(arg);
    case VIDIOC_G_CTRL: return get_or_set_control(arg, false);
    case VIDIOC_S_CTRL: return get_or_set_control(arg, true);
    case VIDIOC_REQBUFS: return request_buffers(arg);
    case VIDIOC_QUERYBUF: return query_buffer(arg);
    case VIDIOC_QBUF: return queue_buffer(arg);
    case VIDIOC_DQBUF: return dequeue(arg);
    case VIDIOC_STREAMON: return stream_on();
    case VIDIOC_STREAMOFF: return stream_off();
    default: return fail(ENOTTY);
  }
}

int FakeV4l2Device::query_capabilities(void* arg) {
  auto* caps = static_cast<v4l2_capability*>(arg);
  *caps = {};
  copy_name(caps->driver, sizeof caps->driver, "simfake");
  copy_name(caps->card, sizeof caps->card, "SIM fake camera");
  copy_name(caps->bus_info, sizeof caps->bus_info, "platform:simfake-0");
  caps->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  caps->capabilities = caps->device_caps | V4L2_CAP_DEVICE_CAPS;
  return 0;
}

int FakeV4l2Device::enumerate_format(void* arg) {
  auto* desc = static_cast<v4l2_fmtdesc*>(arg);
  if (desc->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || desc->index >= formats_.size()) {
    return fail(EINVAL);
  }
  const FakeFormat& f = formats_[desc->index];
  desc->pixelformat = f.fourcc.code;
  copy_name(desc->description, sizeof desc->description, f.description);
  desc->flags = imaging::is_compressed(pixel_format_of(f.fourcc)) ? V4L2_FMT_FLAG_COMPRESSED : 0;
  return 0;
}

int FakeV4l2Device::enumerate_frame_size(void* arg) {
  auto* size = static_cast<v4l2_frmsizeenum*>(arg);
  const FakeFormat* f = find(size->pixel_format);
  if (f == nullptr || size->index >= f->sizes.size()) return fail(EINVAL);
  size->type = V4L2_FRMSIZE_TYPE_DISCRETE;
  size->discrete.width = f->sizes[size->index].first;
  size->discrete.height = f->sizes[size->index].second;
  return 0;
}

int FakeV4l2Device::enumerate_frame_interval(void* arg) {
  auto* interval = static_cast<v4l2_frmivalenum*>(arg);
  const FakeFormat* f = find(interval->pixel_format);
  if (f == nullptr || interval->index >= f->fps.size()) return fail(EINVAL);
  const auto size = std::make_pair(interval->width, interval->height);
  if (std::find(f->sizes.begin(), f->sizes.end(), size) == f->sizes.end()) return fail(EINVAL);
  interval->type = V4L2_FRMIVAL_TYPE_DISCRETE;
  interval->discrete = {1, f->fps[interval->index]};
  return 0;
}

int FakeV4l2Device::get_format(void* arg) {
  auto* format = static_cast<v4l2_format*>(arg);
  if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
  format->fmt.pix = {};
  format->fmt.pix.width = width_;
  format->fmt.pix.height = height_;
  format->fmt.pix.pixelformat = pixelformat_;
  format->fmt.pix.field = V4L2_FIELD_NONE;
  format->fmt.pix.bytesperline = bytes_per_line();
  format->fmt.pix.sizeimage = size_image();
  return 0;
}

// TRY_FMT answers what S_FMT would set; S_FMT also sets it (not while buffers exist).
int FakeV4l2Device::try_or_set_format(void* arg, bool set) {
  auto* format = static_cast<v4l2_format*>(arg);
  if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
  if (set && !buffers_.empty()) return fail(EBUSY);
  // Like real drivers: an unknown format falls back to the first, a size to the closest.
  const FakeFormat* f = find(format->fmt.pix.pixelformat);
  if (f == nullptr) f = &formats_.front();
  auto best = f->sizes.front();
  auto distance = [&](std::pair<std::uint32_t, std::uint32_t> s) {
    return std::llabs(static_cast<long long>(s.first) - format->fmt.pix.width) +
           std::llabs(static_cast<long long>(s.second) - format->fmt.pix.height);
  };
  for (const auto& s : f->sizes) {
    if (distance(s) < distance(best)) best = s;
  }
  if (set) {
    pixelformat_ = f->fourcc.code;
    width_ = best.first;
    height_ = best.second;
  }
  format->fmt.pix.pixelformat = f->fourcc.code;
  format->fmt.pix.width = best.first;
  format->fmt.pix.height = best.second;
  format->fmt.pix.field = V4L2_FIELD_NONE;
  // The line and image sizes of the answered format, whether or not it was set.
  const std::uint32_t saved_format = pixelformat_;
  const std::uint32_t saved_width = width_;
  const std::uint32_t saved_height = height_;
  pixelformat_ = f->fourcc.code;
  width_ = best.first;
  height_ = best.second;
  format->fmt.pix.bytesperline = bytes_per_line();
  format->fmt.pix.sizeimage = size_image();
  pixelformat_ = saved_format;
  width_ = saved_width;
  height_ = saved_height;
  return 0;
}

// G_PARM and S_PARM: S_PARM picks the offered rate closest to the one asked for.
int FakeV4l2Device::stream_parameters(void* arg, bool set) {
  auto* parm = static_cast<v4l2_streamparm*>(arg);
  if (parm->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
  if (set) {
    const auto& tpf = parm->parm.capture.timeperframe;
    const double wanted = tpf.numerator == 0 ? 30.0
                                             : static_cast<double>(tpf.denominator) /
                                                   tpf.numerator;
    const FakeFormat* f = find(pixelformat_);
    std::uint32_t best = fps_;
    if (f != nullptr) {
      for (const std::uint32_t fps : f->fps) {
        if (std::abs(fps - wanted) < std::abs(best - wanted)) best = fps;
      }
    }
    fps_ = best;
  }
  parm->parm.capture = {};
  parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
  parm->parm.capture.timeperframe = {1, fps_};
  return 0;
}

int FakeV4l2Device::query_control(void* arg) {
  auto* query = static_cast<v4l2_queryctrl*>(arg);
  const bool next = (query->id & V4L2_CTRL_FLAG_NEXT_CTRL) != 0;
  const std::uint32_t id = query->id & ~(V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND);
  const FakeControl* found = nullptr;
  for (const auto& c : controls_) {
    if (next ? (c.id > id && (found == nullptr || c.id < found->id)) : c.id == id) found = &c;
  }
  if (found == nullptr) return fail(EINVAL);
  *query = {};
  query->id = found->id;
  query->type = found->type;
  copy_name(query->name, sizeof query->name, found->name);
  query->minimum = found->minimum;
  query->maximum = found->maximum;
  query->step = found->step;
  query->default_value = found->default_value;
  return 0;
}

int FakeV4l2Device::query_menu(void* arg) {
  auto* menu = static_cast<v4l2_querymenu*>(arg);
  for (const auto& c : controls_) {
    if (c.id == menu->id && menu->index < c.menu.size()) {
      copy_name(menu->name, sizeof menu->name, c.menu[menu->index]);
      return 0;
    }
  }
  return fail(EINVAL);
}

int FakeV4l2Device::get_or_set_control(void* arg, bool set) {
  auto* control = static_cast<v4l2_control*>(arg);
  for (auto& c : controls_) {
    if (c.id != control->id) continue;
    if (!set) {
      control->value = c.value;
      return 0;
    }
    if (control->value < c.minimum || control->value > c.maximum) return fail(ERANGE);
    c.value = control->value;
    return 0;
  }
  return fail(EINVAL);
}

int FakeV4l2Device::request_buffers(void* arg) {
  auto* request = static_cast<v4l2_requestbuffers*>(arg);
  if (request->memory != V4L2_MEMORY_MMAP ||
      request->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
    return fail(EINVAL);
  }
  if (streaming_ || mapped_ > 0) return fail(EBUSY);
  free_buffers();
  const std::uint32_t count = std::min<std::uint32_t>(request->count, 8);
  for (std::uint32_t i = 0; i < count; ++i) {
    Buffer buffer;
    buffer.length = size_image();
    buffer.memory = std::make_unique<std::byte[]>(buffer.length);
    buffers_.push_back(std::move(buffer));
  }
  request->count = count;
  return 0;
}

int FakeV4l2Device::query_buffer(void* arg) {
  auto* buffer = static_cast<v4l2_buffer*>(arg);
  if (buffer->index >= buffers_.size() || buffer->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
  buffer->length = static_cast<std::uint32_t>(buffers_[buffer->index].length);
  buffer->m.offset = static_cast<std::uint32_t>(buffer->index * kOffsetStride);
  return 0;
}

int FakeV4l2Device::queue_buffer(void* arg) {
  auto* buffer = static_cast<v4l2_buffer*>(arg);
  if (buffer->index >= buffers_.size() || buffer->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
  Buffer& b = buffers_[buffer->index];
  if (b.queued) return fail(EINVAL);
  b.queued = true;
  queue_.push_back(buffer->index);
  return 0;
}

int FakeV4l2Device::stream_on() {
  if (buffers_.empty()) return fail(EINVAL);
  streaming_ = true;
  return 0;
}

int FakeV4l2Device::stream_off() {
  streaming_ = false;
  for (auto& b : buffers_) b.queued = false;  // STREAMOFF returns every buffer to the app
  queue_.clear();
  return 0;
}

}  // namespace sim::camera::testing
