// SPDX-License-Identifier: Apache-2.0
// The Python module `sim` (built as sim._sim): SIM readers and writers with frames as numpy arrays.
//
// Lifetimes are the point of this file. A borrowed frame's numpy view points into the reader's
// shared-memory mapping, and a loan's view into the writer's; Python code can keep such a view
// after dropping everything else. So every view's numpy `base` is the Python Borrow/Loan object,
// and that object holds a shared_ptr to the reader's (writer's) state: the mapping lives as long
// as the last view, whatever the program closes or deletes first.
#include <pybind11/numpy.h>
#include <pybind11/operators.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "sim/sim.hpp"

namespace py = pybind11;

namespace {

// ---- errors: one exception type whose message is the library's sentence ----

struct SimException : std::runtime_error {
  SimException(std::string message, std::string code_name)
      : std::runtime_error(std::move(message)), code(std::move(code_name)) {}
  std::string code;
};

[[noreturn]] void raise(const sim::Error& error) {
  throw SimException(error.message, sim::to_string(error.code));
}

void raise_if_error(const sim::Expected<void>& result) {
  if (!result) raise(result.error());
}

// ---- numpy shapes of the layouts ----

py::object numpy_dtype(const py::dict& spec) {
  return py::module_::import("numpy").attr("dtype")(spec);
}

// The structured dtypes of the point types; field names and offsets are sim::LidarPoint's.
py::dtype point_dtype(sim::PointType type) {
  using py::make_tuple;
  py::dict spec;
  switch (type) {
    case sim::PointType::lidar_point:
      spec["names"] = make_tuple("x", "y", "z", "intensity", "time_offset_ns", "ring", "return_index");
      spec["formats"] = make_tuple("<f4", "<f4", "<f4", "<f4", "<u4", "<u2", "u1");
      spec["offsets"] = make_tuple(offsetof(sim::LidarPoint, x), offsetof(sim::LidarPoint, y),
                                   offsetof(sim::LidarPoint, z), offsetof(sim::LidarPoint, intensity),
                                   offsetof(sim::LidarPoint, time_offset_ns),
                                   offsetof(sim::LidarPoint, ring),
                                   offsetof(sim::LidarPoint, return_index));
      spec["itemsize"] = sizeof(sim::LidarPoint);
      break;
    case sim::PointType::xyz32:
      spec["names"] = make_tuple("x", "y", "z");
      spec["formats"] = make_tuple("<f4", "<f4", "<f4");
      break;
    case sim::PointType::xyzi32:
      spec["names"] = make_tuple("x", "y", "z", "intensity");
      spec["formats"] = make_tuple("<f4", "<f4", "<f4", "<f4");
      break;
    case sim::PointType::unknown: return py::dtype("u1");
  }
  return py::reinterpret_borrow<py::dtype>(numpy_dtype(spec));
}

// A numpy array over `size` bytes at `data` shaped by the layout: images (h, w, c) of uint8 or
// uint16, points a structured array, everything else (raw bytes, MJPEG, a frame that does not
// fill its layout) flat uint8. `base` keeps the memory alive.
py::array shaped_array(const sim::Layout& layout, const std::byte* data, std::uint64_t size,
                       py::handle base, bool writable) {
  auto* ptr = const_cast<std::byte*>(data);
  py::array array;
  if (layout.kind == sim::LayoutKind::image && layout.image.frame_bytes() != 0 &&
      size >= layout.image.frame_bytes() && layout.image.channels != 0) {
    const sim::ImageLayout& im = layout.image;
    const bool wide = im.bit_depth > 8;
    const py::ssize_t item = wide ? 2 : 1;
    const py::dtype dtype = wide ? py::dtype("<u2") : py::dtype("u1");
    array = py::array(dtype, {py::ssize_t(im.height), py::ssize_t(im.width), py::ssize_t(im.channels)},
                      {py::ssize_t(im.stride), py::ssize_t(im.channels) * item, item}, ptr, base);
  } else if (layout.kind == sim::LayoutKind::points && layout.points.type != sim::PointType::unknown &&
             layout.points.point_size != 0) {
    const py::ssize_t count = py::ssize_t(size / layout.points.point_size);
    array = py::array(point_dtype(layout.points.type), {count}, {py::ssize_t(layout.points.point_size)},
                      ptr, base);
  } else {
    array = py::array(py::dtype("u1"), {py::ssize_t(size)}, {py::ssize_t(1)}, ptr, base);
  }
  if (!writable) array.attr("flags").attr("writeable") = false;
  return array;
}

// How long one wait of a Python call lasts at most: between two, the call takes the GIL back to
// let Ctrl-C (and other signals) raise, and gives the reader's mutex to other threads.
constexpr std::chrono::nanoseconds kPythonWaitSlice = std::chrono::milliseconds(50);

// Runs `call` (without the GIL) with `mutex` held, as a caller holding the GIL: the GIL is given
// up while the mutex is awaited, so a thread waiting on the same object never stops the others.
template <typename Mutex, typename Call>
auto locked(Mutex& mutex, Call&& call) {
  py::gil_scoped_release release;
  std::lock_guard lock(mutex);
  return call();
}

// Seconds from Python (None: forever) as nanoseconds, saturating like the C++ API's timeouts.
std::chrono::nanoseconds to_ns(std::optional<double> seconds) {
  if (!seconds) return sim::kForever;
  if (!(*seconds >= 0)) throw py::value_error("a timeout is a number of seconds, 0 or more (or None: forever)");
  if (*seconds * 1e9 >= 9.2e18) return sim::kForever;
  return std::chrono::nanoseconds(static_cast<std::int64_t>(*seconds * 1e9));
}

// ---- reader ----

// What a Python Reader shares with the frames it hands out. `open` is cleared by close(); the
// sim::Reader itself goes with the last Python object that needs it.
struct ReaderState {
  std::mutex mutex;  // one call into the sim::Reader at a time (calls run without the GIL)
  std::optional<sim::Reader> reader;
  bool open = true;
  std::atomic<sim::ReadStatus> last_status{sim::ReadStatus::no_new_frame};  // read without the mutex
  std::string name;  // fixed at open: readable without the mutex

  // What other threads may ask while one waits in the reader for seconds (review M4, L9): copied
  // after every call into the reader, read under their own short-lived lock.
  struct Snapshot {
    sim::ReaderStats stats;
    std::uint64_t capacity = 0;
    sim::Layout layout;
  };
  mutable std::mutex snapshot_mutex;
  Snapshot snapshot;

  // Called with `mutex` held.
  sim::Reader& usable() {
    if (!open) throw SimException("the reader is closed: open a new sim.Reader", "closed");
    return *reader;
  }
  void take_snapshot() {  // with `mutex` held: the reader may have moved to a new region
    std::lock_guard lock(snapshot_mutex);
    snapshot = {reader->stats(), reader->capacity(), reader->layout()};
  }
  Snapshot latest() const {
    std::lock_guard lock(snapshot_mutex);
    return snapshot;
  }
};

struct FrameObject {
  py::object array;
  sim::FrameInfo info;
};

// A sim::Borrow keeps the region it points into mapped (whatever happens to the stream or the
// Reader), so the Python object only has to live as long as its numpy views: it is their base.
class BorrowObject {
 public:
  explicit BorrowObject(sim::Borrow borrow) : borrow_(std::move(borrow)) {}
  const sim::FrameInfo& info() const { return borrow_.info(); }
  bool still_valid() const { return borrow_.still_valid(); }
  const sim::Borrow& borrow() const { return borrow_; }

 private:
  sim::Borrow borrow_;
};

class ReaderObject {
 public:
  ReaderObject(const std::string& name, double stale_after, bool verify_checksum,
               const std::string& trust_owner, const std::string& trust_group)
      : state_(std::make_shared<ReaderState>()) {
    sim::ReaderOptions options;
    options.stale_after = to_ns(stale_after);
    options.verify_checksum = verify_checksum;
    auto trust = sim::Trust::parse(trust_owner, trust_group);
    if (!trust) raise(trust.error());
    options.trust = *trust;
    auto reader = sim::Reader::open(name, options);
    if (!reader) raise(reader.error());
    state_->reader.emplace(std::move(reader.value()));
    state_->name = name;
    state_->take_snapshot();
    buffer_ = py::array_t<std::uint8_t>(py::ssize_t(state_->reader->capacity()));
  }

  // Runs `call(reader)` with the reader's mutex held and the GIL released, then refreshes what
  // other threads read without the mutex.
  template <typename Call>
  auto with_reader(Call&& call) {
    return locked(state_->mutex, [&] {
      sim::Reader& reader = state_->usable();
      auto result = call(reader);
      state_->take_snapshot();
      return result;
    });
  }

  py::object read() { return read_copy(); }
  // wait() (in slices, interruptible), then read().
  py::object read_next(std::optional<double> timeout) {
    if (!wait(timeout)) return py::none();
    return read_copy();
  }

  // A copy: each frame gets its own numpy buffer (the last one is reused only if nobody kept it).
  py::object read_copy() {
    for (int attempt = 0; attempt < 2; ++attempt) {
      py::array_t<std::uint8_t> out = fresh_buffer();
      auto span = std::span<std::byte>(reinterpret_cast<std::byte*>(out.mutable_data()),
                                       std::size_t(out.size()));
      sim::FrameInfo info;
      sim::ReadStatus status;
      std::uint64_t capacity = 0;
      with_reader([&](sim::Reader& reader) {
        status = reader.read(span, info);
        state_->last_status = status;
        capacity = reader.capacity();
        return 0;
      });
      if (status == sim::ReadStatus::buffer_too_small) {  // a new writer made the stream larger
        buffer_ = py::array_t<std::uint8_t>(py::ssize_t(capacity));
        continue;
      }
      if (status == sim::ReadStatus::region_invalid) {
        throw SimException("the stream " + name() + " no longer passes validation: open it again",
                           "region_invalid");
      }
      if (status != sim::ReadStatus::new_frame) return py::none();
      buffer_ = py::array_t<std::uint8_t>();  // the frame's array owns this buffer now
      return py::cast(FrameObject{shaped_array(info.layout, reinterpret_cast<const std::byte*>(out.data()),
                                               info.size, out, true),
                                  info});
    }
    return py::none();
  }

  // Waits in slices of kPythonWaitSlice; between them the GIL is taken back so a signal
  // (KeyboardInterrupt) raises at once, and the mutex is let go so other threads' calls on this
  // reader wait one slice at most.
  bool wait(std::optional<double> timeout) {
    const std::chrono::nanoseconds budget = to_ns(timeout);
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      const std::chrono::nanoseconds elapsed = std::chrono::steady_clock::now() - start;
      const std::chrono::nanoseconds left = budget == sim::kForever ? sim::kForever : budget - elapsed;
      const std::chrono::nanoseconds slice = std::max(std::min(left, kPythonWaitSlice), std::chrono::nanoseconds(0));
      const sim::ReadStatus status = with_reader([&](sim::Reader& reader) {
        const sim::ReadStatus waited = reader.wait(slice);
        state_->last_status = waited;
        return waited;
      });
      if (status == sim::ReadStatus::new_frame) return true;
      if (left <= slice) return false;  // the whole timeout has passed
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }

  py::object borrow() {
    sim::Borrow borrow = with_reader([&](sim::Reader& reader) {
      sim::Borrow b = reader.borrow();
      state_->last_status = b.status();
      return b;
    });
    if (borrow.status() == sim::ReadStatus::region_invalid) {
      throw SimException("the stream " + name() + " no longer passes validation: open it again",
                         "region_invalid");
    }
    if (borrow.status() != sim::ReadStatus::new_frame) return py::none();
    return py::cast(std::make_unique<BorrowObject>(std::move(borrow)));
  }

  bool writer_alive() {
    return with_reader([](sim::Reader& reader) { return reader.writer_alive(); });
  }

  // nullopt: the stream has no description; raises SimError when it is damaged.
  std::optional<sim::SensorInfo> sensor_info() {
    auto info = with_reader([](sim::Reader& reader) { return reader.sensor_info(); });
    if (!info) raise(info.error());
    return std::move(*info);
  }

  // nullopt: the stream has no clock record (yet); raises SimError when it is damaged.
  std::optional<sim::ClockStatus> clock() {
    auto clock = with_reader([](sim::Reader& reader) { return reader.clock(); });
    if (!clock) raise(clock.error());
    return std::move(*clock);
  }

  void close() {
    locked(state_->mutex, [&] { state_->open = false; });  // the mapping goes with the last borrow
  }
  bool closed() const { return !state_->open; }
  sim::ReadStatus last_status() const { return state_->last_status; }
  std::string name() const { return state_->name; }
  // As of the last call into the reader: they never wait for a thread waiting in read_next.
  std::uint64_t capacity() const { return state_->latest().capacity; }
  sim::Layout layout() const { return state_->latest().layout; }
  sim::ReaderStats stats() const { return state_->latest().stats; }

 private:

  py::array_t<std::uint8_t> fresh_buffer() {
    if (buffer_.size() == 0 || buffer_.ref_count() > 1) {
      buffer_ = py::array_t<std::uint8_t>(py::ssize_t(capacity()));
    }
    return buffer_;
  }
  std::shared_ptr<ReaderState> state_;
  py::array_t<std::uint8_t> buffer_;
};

// ---- writer ----

struct WriterState {
  std::mutex mutex;
  std::optional<sim::Writer> writer;
  bool open = true;

  sim::Writer& usable() {
    if (!open) throw SimException("the writer is closed: create a new sim.Writer", "closed");
    return *writer;
  }
};

void raise_if_failed(sim::WriteStatus status, std::uint64_t size, std::uint64_t capacity) {
  switch (status) {
    case sim::WriteStatus::ok: return;
    case sim::WriteStatus::too_large:
      throw SimException("a frame of " + std::to_string(size) + " bytes does not fit the stream's " +
                             std::to_string(capacity) +
                             " bytes: create the writer with a larger capacity",
                         "too_large");
    case sim::WriteStatus::closed:
      throw SimException("the writer is closed: create a new sim.Writer", "closed");
    case sim::WriteStatus::loan_open:
      throw SimException("a loan of this writer is still open: commit it or delete it first",
                         "loan_open");
  }
}

// Until it is committed, the Python object holds the writer's state, so the sim::Loan never
// outlives its Writer. It always holds the region's mapping, so its views stay readable as long as
// they live; a committed loan lets go of the writer (review L8: a leftover view kept the writer's
// lock, and the stream, for as long as it lived).
class LoanObject {
 public:
  LoanObject(std::shared_ptr<WriterState> state, sim::Loan loan, sim::Layout layout,
             std::shared_ptr<const void> mapping)
      : state_(std::move(state)), loan_(std::move(loan)), layout_(layout), mapping_(std::move(mapping)) {}
  LoanObject(const LoanObject&) = delete;
  LoanObject& operator=(const LoanObject&) = delete;
  ~LoanObject() {
    if (state_) locked(state_->mutex, [&] { loan_ = sim::Loan(); });  // touches the writer's state
  }

  // A writable view of the whole slot; its base is this Loan, which keeps the mapping alive.
  py::array array(py::handle self) const {
    return shaped_array(layout_, loan_.bytes().data(), loan_.bytes().size(), self, true);
  }
  std::uint64_t capacity() const { return loan_.bytes().size(); }

  void commit(std::optional<std::uint64_t> nbytes, std::optional<std::int64_t> stamp_ns,
              std::int64_t receive_ns) {
    if (!loan_.valid()) throw SimException("this loan was already committed: take a new loan", "committed");
    const std::uint64_t size = nbytes.value_or(default_size());
    const std::int64_t stamp = stamp_ns.value_or(sim::realtime_ns());
    const std::uint64_t slot_capacity = capacity();
    const sim::WriteStatus status = locked(state_->mutex, [&] {
      if (!state_->open) {  // a closed writer publishes nothing more (review L8)
        loan_ = sim::Loan();
        return sim::WriteStatus::closed;
      }
      return std::move(loan_).commit(size, stamp, receive_ns);  // ends the loan whatever the outcome
    });
    state_.reset();  // the loan is over: views need only the mapping, not the writer
    raise_if_failed(status, size, slot_capacity);
  }

 private:
  std::uint64_t default_size() const {
    const std::uint64_t full = layout_.min_capacity();
    return full != 0 ? std::min<std::uint64_t>(full, capacity()) : capacity();
  }
  std::shared_ptr<WriterState> state_;  // null once committed
  sim::Loan loan_;
  sim::Layout layout_;
  std::shared_ptr<const void> mapping_;
};

class WriterObject {
 public:
  WriterObject(const std::string& name, const sim::Layout& layout, std::uint64_t capacity,
               bool checksum, std::uint32_t mode, double heartbeat_period,
               std::optional<sim::SensorInfo> sensor)
      : state_(std::make_shared<WriterState>()) {
    sim::StreamSpec spec;
    spec.sensor = std::move(sensor);
    spec.name = name;
    spec.layout = layout;
    spec.capacity = capacity;
    spec.checksum = checksum;
    spec.mode = mode;
    spec.heartbeat_period = std::chrono::duration_cast<std::chrono::milliseconds>(to_ns(heartbeat_period));
    std::optional<sim::Expected<sim::Writer>> writer;
    {
      py::gil_scoped_release release;
      writer.emplace(sim::Writer::create(spec));
    }
    if (!*writer) raise(writer->error());
    state_->writer.emplace(std::move(writer->value()));
    name_ = state_->writer->name();
    capacity_ = state_->writer->capacity();
    layout_ = state_->writer->layout();
  }

  void write(const py::object& data, std::optional<std::int64_t> stamp_ns, std::int64_t receive_ns) {
    Py_buffer view;
    if (PyObject_GetBuffer(data.ptr(), &view, PyBUF_C_CONTIGUOUS) != 0) {
      PyErr_Clear();
      throw py::type_error("write() takes a C-contiguous buffer (a numpy array, bytes, bytearray): "
                           "pass numpy.ascontiguousarray(frame)");
    }
    const std::int64_t stamp = stamp_ns.value_or(sim::realtime_ns());
    sim::WriteStatus status = sim::WriteStatus::ok;
    std::uint64_t capacity = 0;
    try {
      py::gil_scoped_release release;
      std::lock_guard lock(state_->mutex);
      sim::Writer& writer = state_->usable();
      capacity = writer.capacity();
      status = writer.write(std::span<const std::byte>(static_cast<const std::byte*>(view.buf),
                                                       std::size_t(view.len)),
                            stamp, receive_ns);
    } catch (...) {
      PyBuffer_Release(&view);
      throw;
    }
    const auto size = std::uint64_t(view.len);
    PyBuffer_Release(&view);
    raise_if_failed(status, size, capacity);
  }

  std::unique_ptr<LoanObject> loan() {
    sim::Layout layout;
    std::shared_ptr<const void> mapping;
    sim::Loan loan = locked(state_->mutex, [&] {
      sim::Writer& writer = state_->usable();
      layout = writer.layout();
      mapping = writer.mapping();
      return writer.loan();
    });
    if (!loan.valid()) raise_if_failed(sim::WriteStatus::loan_open, 0, 0);
    return std::make_unique<LoanObject>(state_, std::move(loan), layout, std::move(mapping));
  }

  void set_sensor_info(const sim::SensorInfo& info) {
    raise_if_error(locked(state_->mutex, [&] { return state_->usable().set_sensor_info(info); }));
  }

  void set_clock(const sim::ClockStatus& clock) {
    raise_if_error(locked(state_->mutex, [&] { return state_->usable().set_clock(clock); }));
  }

  void close() {
    py::gil_scoped_release release;
    std::lock_guard lock(state_->mutex);
    state_->open = false;
    // An open loan still needs the writer; otherwise the writer lock goes now.
    if (state_.use_count() == 1 && state_->writer) {
      last_seq_ = state_->writer->last_seq();
      state_->writer.reset();
    }
  }
  bool closed() const { return !state_->open; }
  // Fixed at creation, so they stay answerable after close() let the writer go.
  std::string name() const { return name_; }
  std::uint64_t capacity() const { return capacity_; }
  sim::Layout layout() const { return layout_; }
  std::uint64_t last_seq() {
    return locked(state_->mutex, [&] { return state_->writer ? state_->writer->last_seq() : last_seq_; });
  }

 private:
  std::shared_ptr<WriterState> state_;
  std::string name_;
  std::uint64_t capacity_ = 0;
  sim::Layout layout_;
  std::uint64_t last_seq_ = 0;  // when close() let the writer go
};

sim::PixelFormat pixel_format_from(const py::handle& format) {
  if (py::isinstance<sim::PixelFormat>(format)) return format.cast<sim::PixelFormat>();
  const auto text = format.cast<std::string>();
  for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(sim::PixelFormat::mjpeg); ++i) {
    const auto candidate = static_cast<sim::PixelFormat>(i);
    if (text == sim::to_string(candidate)) return candidate;
  }
  throw py::value_error("'" + text + "' is not a pixel format: use one of sim.PixelFormat's names");
}

sim::PointType point_type_from(const py::handle& type) {
  if (py::isinstance<sim::PointType>(type)) return type.cast<sim::PointType>();
  const auto text = type.cast<std::string>();
  for (std::uint32_t i = 1; i <= static_cast<std::uint32_t>(sim::PointType::lidar_point); ++i) {
    const auto candidate = static_cast<sim::PointType>(i);
    if (text == sim::to_string(candidate)) return candidate;
  }
  throw py::value_error("'" + text + "' is not a point type: use xyz32, xyzi32 or lidar_point");
}

py::dict info_to_dict(const sim::FrameInfo& info) {
  py::dict d;
  d["seq"] = info.seq;
  d["stamp_ns"] = info.stamp_ns;
  d["publish_ns"] = info.publish_ns;
  d["receive_ns"] = info.receive_ns;
  d["size"] = info.size;
  d["sensor_generation"] = info.sensor_generation;
  d["clock_generation"] = info.clock_generation;
  d["stamp_clock"] = sim::to_string(info.stamp_clock);
  return d;
}

// ---- the sensor description: fixed-size C++ arrays as numpy arrays (copies) ----

py::array_t<double> numpy_of(const double* values, std::vector<py::ssize_t> shape) {
  py::array_t<double> out(shape);
  std::copy(values, values + out.size(), out.mutable_data());
  return out;
}

// Any array-like of `N` numbers (a 3x3 nested list for K, a flat tuple…), row-major.
template <std::size_t N>
std::array<double, N> numbers(const py::handle& values, const char* what) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!array || std::size_t(array.size()) != N) {
    throw py::value_error(std::string(what) + " takes " + std::to_string(N) + " numbers");
  }
  std::array<double, N> out{};
  std::copy(array.data(), array.data() + N, out.begin());
  return out;
}

std::vector<double> number_list(const py::handle& values, const char* what) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!array || array.ndim() > 1) throw py::value_error(std::string(what) + " takes a list of numbers");
  return {array.data(), array.data() + array.size()};
}

// The clock record: its enums and ClockStatus (sim/clock_status.hpp).
void bind_clock(py::module_& m) {
  py::enum_<sim::ClockSource>(m, "ClockSource", "Where a clock gets its time from.")
      .value("unknown", sim::ClockSource::unknown)
      .value("host", sim::ClockSource::host)
      .value("ptp", sim::ClockSource::ptp)
      .value("gptp", sim::ClockSource::gptp)
      .value("pps_nmea", sim::ClockSource::pps_nmea)
      .value("sync_pulse", sim::ClockSource::sync_pulse)
      .value("free_running", sim::ClockSource::free_running)
      .value("replayed", sim::ClockSource::replayed);
  py::enum_<sim::ClockState>(m, "ClockState", "What a clock's synchronisation says of itself.")
      .value("unknown", sim::ClockState::unknown)
      .value("locked", sim::ClockState::locked)
      .value("acquiring", sim::ClockState::acquiring)
      .value("holdover", sim::ClockState::holdover)
      .value("free_running", sim::ClockState::free_running);
  py::enum_<sim::ClockVerdict>(m, "ClockVerdict", "The verdict on a stream's clock.")
      .value("unknown", sim::ClockVerdict::unknown)
      .value("ok", sim::ClockVerdict::ok)
      .value("warn", sim::ClockVerdict::warn)
      .value("error", sim::ClockVerdict::error);
  py::enum_<sim::StampClock>(m, "StampClock", "Which clock a frame's stamp is in.")
      .value("unknown", sim::StampClock::unknown)
      .value("sensor", sim::StampClock::sensor)
      .value("sensor_tai_corrected", sim::StampClock::sensor_tai_corrected)
      .value("host_arrival", sim::StampClock::host_arrival);
  using C = sim::ClockStatus;
  py::class_<C>(m, "ClockStatus", "A stream's clock: reported, measured against the host, judged.")
      .def(py::init<>())
      .def_readwrite("source", &C::source)
      .def_readwrite("state", &C::state)
      .def_readwrite("ptp_domain", &C::ptp_domain, "-1: unknown or not PTP.")
      .def_readwrite("offset_from_master_ns", &C::offset_from_master_ns, "As reported; None when not.")
      .def_readwrite("path_delay_ns", &C::path_delay_ns)
      .def_readwrite("grandmaster", &C::grandmaster, "Clock identity as ptp4l prints it; '' unknown.")
      .def_readwrite("utc_offset_s", &C::utc_offset_s, "TAI - UTC announced by the master; None unknown.")
      .def_readwrite("ptp_timescale", &C::ptp_timescale)
      .def_readwrite("tai_correction_ns", &C::tai_correction_ns)
      .def_readwrite("reported_ns", &C::reported_ns)
      .def_readwrite("offset_to_host_ns", &C::offset_to_host_ns,
                     "Measured median of sensor - host time per packet, ns; None until measured.")
      .def_readwrite("spread_ns", &C::spread_ns)
      .def_readwrite("drift_ppm", &C::drift_ppm)
      .def_readwrite("steps", &C::steps)
      .def_readwrite("last_step_ns", &C::last_step_ns)
      .def_readwrite("packets_measured", &C::packets_measured)
      .def_readwrite("measured_ns", &C::measured_ns)
      .def_readwrite("verdict", &C::verdict)
      .def_readwrite("problem", &C::problem, "One sentence; '' when ok.")
      .def_readwrite("stamps", &C::stamps, "The clock the frames' stamps are in now.")
      .def("summary", [](const C& c) { return sim::summary(c); }, "One line for people.")
      .def("problem_text", &sim::clock_status_problem, "Why it cannot be stored, or ''.")
      .def(py::self == py::self)
      .def("__repr__", [](const C& c) { return "<sim.ClockStatus " + sim::summary(c) + ">"; });
}

// TimeBase, PointTime and Mounting.
void bind_sensor_basics(py::module_& m) {
  py::enum_<sim::TimeBase>(m, "TimeBase", "Which clock a stream's stamps are in.")
      .value("unknown", sim::TimeBase::unknown)
      .value("host", sim::TimeBase::host)
      .value("sensor_synchronized", sim::TimeBase::sensor_synchronized)
      .value("sensor_free_running", sim::TimeBase::sensor_free_running);
  py::enum_<sim::PointTime>(m, "PointTime", "What a LiDAR point's time_offset_ns means.")
      .value("none", sim::PointTime::none)
      .value("after_frame_stamp", sim::PointTime::after_frame_stamp);

  py::class_<sim::Mounting>(m, "Mounting",
                            "Where the sensor sits in its parent frame: translation (m) and rotation "
                            "(unit quaternion x, y, z, w), numpy copies; assign whole arrays to change them.")
      .def(py::init([](const py::object& translation, const py::object& rotation) {
             sim::Mounting mounting;
             mounting.translation = numbers<3>(translation, "translation");
             mounting.rotation = numbers<4>(rotation, "rotation");
             return mounting;
           }),
           py::arg("translation") = py::make_tuple(0.0, 0.0, 0.0),
           py::arg("rotation") = py::make_tuple(0.0, 0.0, 0.0, 1.0))
      .def_static("from_xyz_rpy", &sim::Mounting::from_xyz_rpy, py::arg("x"), py::arg("y"), py::arg("z"),
                  py::arg("roll"), py::arg("pitch"), py::arg("yaw"),
                  "From metres and radians as static_transform_publisher takes them (tf2's setRPY).")
      .def_property(
          "translation", [](const sim::Mounting& mnt) { return numpy_of(mnt.translation.data(), {3}); },
          [](sim::Mounting& mnt, const py::object& v) { mnt.translation = numbers<3>(v, "translation"); })
      .def_property(
          "rotation", [](const sim::Mounting& mnt) { return numpy_of(mnt.rotation.data(), {4}); },
          [](sim::Mounting& mnt, const py::object& v) { mnt.rotation = numbers<4>(v, "rotation"); })
      .def(py::self == py::self);

}

// CameraCalibration and its RegionOfInterest.
void bind_calibration(py::module_& m) {
  using Roi = sim::CameraCalibration::RegionOfInterest;
  py::class_<Roi>(m, "RegionOfInterest", "A calibration's region of interest (all 0: the whole image).")
      .def(py::init([](std::uint32_t x_offset, std::uint32_t y_offset, std::uint32_t height,
                       std::uint32_t width, bool do_rectify) {
             return Roi{x_offset, y_offset, height, width, do_rectify};
           }),
           py::kw_only(), py::arg("x_offset") = 0, py::arg("y_offset") = 0, py::arg("height") = 0,
           py::arg("width") = 0, py::arg("do_rectify") = false)
      .def_readwrite("x_offset", &Roi::x_offset)
      .def_readwrite("y_offset", &Roi::y_offset)
      .def_readwrite("height", &Roi::height)
      .def_readwrite("width", &Roi::width)
      .def_readwrite("do_rectify", &Roi::do_rectify)
      .def(py::self == py::self);

  using Calibration = sim::CameraCalibration;
  py::class_<Calibration>(m, "CameraCalibration",
                          "A camera's calibration as sensor_msgs/CameraInfo holds it. d, k (3x3), r (3x3) "
                          "and p (3x4) are numpy copies; assign whole arrays to change them.")
      .def(py::init([](std::uint32_t width, std::uint32_t height, const std::string& camera_name,
                       const std::string& distortion_model, const py::object& d, const py::object& k,
                       const py::object& r, const py::object& p, std::uint32_t binning_x,
                       std::uint32_t binning_y, const std::optional<Roi>& roi) {
             Calibration c;
             c.width = width;
             c.height = height;
             c.camera_name = camera_name;
             c.distortion_model = distortion_model;
             c.d = number_list(d, "d");
             if (!k.is_none()) c.k = numbers<9>(k, "k");
             if (!r.is_none()) c.r = numbers<9>(r, "r");
             if (!p.is_none()) c.p = numbers<12>(p, "p");
             c.binning_x = binning_x;
             c.binning_y = binning_y;
             if (roi) c.roi = *roi;
             return c;
           }),
           py::kw_only(), py::arg("width") = 0, py::arg("height") = 0, py::arg("camera_name") = "",
           py::arg("distortion_model") = "plumb_bob", py::arg("d") = py::tuple(), py::arg("k") = py::none(),
           py::arg("r") = py::none(), py::arg("p") = py::none(), py::arg("binning_x") = 0,
           py::arg("binning_y") = 0, py::arg("roi") = py::none())
      .def_readwrite("width", &Calibration::width)
      .def_readwrite("height", &Calibration::height)
      .def_readwrite("camera_name", &Calibration::camera_name)
      .def_readwrite("distortion_model", &Calibration::distortion_model)
      .def_property(
          "d", [](const Calibration& c) { return numpy_of(c.d.data(), {py::ssize_t(c.d.size())}); },
          [](Calibration& c, const py::object& v) { c.d = number_list(v, "d"); })
      .def_property(
          "k", [](const Calibration& c) { return numpy_of(c.k.data(), {3, 3}); },
          [](Calibration& c, const py::object& v) { c.k = numbers<9>(v, "k"); })
      .def_property(
          "r", [](const Calibration& c) { return numpy_of(c.r.data(), {3, 3}); },
          [](Calibration& c, const py::object& v) { c.r = numbers<9>(v, "r"); })
      .def_property(
          "p", [](const Calibration& c) { return numpy_of(c.p.data(), {3, 4}); },
          [](Calibration& c, const py::object& v) { c.p = numbers<12>(v, "p"); })
      .def_readwrite("binning_x", &Calibration::binning_x)
      .def_readwrite("binning_y", &Calibration::binning_y)
      .def_readwrite("roi", &Calibration::roi)
      .def("summary", [](const Calibration& c) { return sim::summary(c); }, "\"1920x1200 plumb_bob fx=… fy=… cx=… cy=…\"")
      .def(py::self == py::self);

}

// SensorIdentity, SensorInfo and frame_id_problem (after the types they hold).
void bind_sensor_info(py::module_& m) {
  bind_sensor_basics(m);
  bind_calibration(m);
  using Calibration = sim::CameraCalibration;
  py::class_<sim::SensorIdentity>(m, "SensorIdentity", "The unit that makes the stream; \"\" is unknown.")
      .def(py::init([](std::string vendor, std::string model, std::string serial, std::string firmware) {
             return sim::SensorIdentity{std::move(vendor), std::move(model), std::move(serial),
                                        std::move(firmware)};
           }),
           py::kw_only(), py::arg("vendor") = "", py::arg("model") = "", py::arg("serial") = "",
           py::arg("firmware") = "")
      .def_readwrite("vendor", &sim::SensorIdentity::vendor)
      .def_readwrite("model", &sim::SensorIdentity::model)
      .def_readwrite("serial", &sim::SensorIdentity::serial)
      .def_readwrite("firmware", &sim::SensorIdentity::firmware)
      .def(py::self == py::self);

  py::class_<sim::SensorInfo>(m, "SensorInfo",
                              "What a stream says about its sensor: frame, mounting, calibration, identity, "
                              "time base (C++ sim::SensorInfo).")
      .def(py::init([](std::string frame_id, std::string parent_frame, std::optional<sim::Mounting> mounting,
                       std::optional<Calibration> calibration, std::optional<sim::SensorIdentity> identity,
                       std::string calibration_source, sim::TimeBase time_base, std::string time_sync,
                       sim::PointTime point_time) {
             sim::SensorInfo info;
             info.frame_id = std::move(frame_id);
             info.parent_frame = std::move(parent_frame);
             info.mounting = std::move(mounting);
             info.calibration = std::move(calibration);
             if (identity) info.identity = std::move(*identity);
             info.calibration_source = std::move(calibration_source);
             info.time_base = time_base;
             info.time_sync = std::move(time_sync);
             info.point_time = point_time;
             return info;
           }),
           py::kw_only(), py::arg("frame_id"), py::arg("parent_frame") = "base_link",
           py::arg("mounting") = py::none(), py::arg("calibration") = py::none(),
           py::arg("identity") = py::none(), py::arg("calibration_source") = "",
           py::arg("time_base") = sim::TimeBase::unknown, py::arg("time_sync") = "",
           py::arg("point_time") = sim::PointTime::none)
      .def_readwrite("frame_id", &sim::SensorInfo::frame_id)
      .def_readwrite("parent_frame", &sim::SensorInfo::parent_frame)
      .def_readwrite("mounting", &sim::SensorInfo::mounting, "A Mounting, or None when it is not known.")
      .def_readwrite("calibration", &sim::SensorInfo::calibration, "A CameraCalibration, or None.")
      .def_readwrite("identity", &sim::SensorInfo::identity)
      .def_readwrite("calibration_source", &sim::SensorInfo::calibration_source)
      .def_readwrite("time_base", &sim::SensorInfo::time_base)
      .def_readwrite("time_sync", &sim::SensorInfo::time_sync)
      .def_readwrite("point_time", &sim::SensorInfo::point_time)
      .def("problem", &sim::sensor_info_problem,
           "One sentence saying why a writer would refuse this description, or \"\".")
      .def(py::self == py::self)
      .def("__repr__", [](const sim::SensorInfo& i) {
        return "<sim.SensorInfo frame_id=" + i.frame_id + " parent_frame=" + i.parent_frame +
               (i.calibration ? " calibration=" + sim::summary(*i.calibration) : std::string()) + ">";
      });
  m.def("frame_id_problem", &sim::frame_id_problem, py::arg("frame"),
        "One sentence saying why `frame` is not a valid frame name, or \"\".");
}

// SimError: the library's one-sentence explanation, with its kind in `code`.
void bind_errors(py::module_& m) {
  static py::exception<SimException> sim_error(m, "SimError", PyExc_RuntimeError);
  sim_error.doc() = "An error from SIM; str(e) is the library's one-sentence explanation, e.code its kind.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SimException& e) {
      py::object error = py::handle(sim_error.ptr())(e.what());  // an instance, to attach .code
      error.attr("code") = e.code;
      PyErr_SetObject(sim_error.ptr(), error.ptr());
    }
  });
}

// The enumerations: ReadStatus, PixelFormat, PointType, LayoutKind.
void bind_enums(py::module_& m) {
  py::enum_<sim::ReadStatus>(m, "ReadStatus", "Why a read returned what it did (Reader.last_status).")
      .value("new_frame", sim::ReadStatus::new_frame)
      .value("no_new_frame", sim::ReadStatus::no_new_frame)
      .value("writer_gone", sim::ReadStatus::writer_gone)
      .value("stale", sim::ReadStatus::stale)
      .value("checksum_mismatch", sim::ReadStatus::checksum_mismatch)
      .value("buffer_too_small", sim::ReadStatus::buffer_too_small)
      .value("overrun", sim::ReadStatus::overrun)
      .value("region_invalid", sim::ReadStatus::region_invalid);

  py::enum_<sim::PixelFormat> pixel(m, "PixelFormat", "Pixel format of an image stream.");
  for (std::uint32_t i = 0; i <= static_cast<std::uint32_t>(sim::PixelFormat::mjpeg); ++i) {
    const auto f = static_cast<sim::PixelFormat>(i);
    pixel.value(sim::to_string(f), f);
  }
  py::enum_<sim::PointType> point(m, "PointType", "Point type of a LiDAR stream.");
  for (std::uint32_t i = 0; i <= static_cast<std::uint32_t>(sim::PointType::lidar_point); ++i) {
    const auto t = static_cast<sim::PointType>(i);
    point.value(sim::to_string(t), t);
  }
  py::enum_<sim::LayoutKind>(m, "LayoutKind", "What a stream's frames are.")
      .value("bytes", sim::LayoutKind::bytes)
      .value("image", sim::LayoutKind::image)
      .value("points", sim::LayoutKind::points);
}

// Layout: what a stream's payload looks like.
void bind_layout(py::module_& m) {
  py::class_<sim::Layout>(m, "Layout", "What a stream's payload looks like (stored in the stream).")
      .def_static("raw", &sim::Layout::raw, "Raw bytes.")
      .def_static(
          "image",
          [](std::uint32_t width, std::uint32_t height, const py::object& format) {
            return sim::Layout::of(sim::ImageLayout::packed(width, height, pixel_format_from(format)));
          },
          py::arg("width"), py::arg("height"), py::arg("format"),
          "A packed image, e.g. Layout.image(640, 480, 'bgr8'); frames read as (height, width, channels).")
      .def_static(
          "points",
          [](std::uint64_t max_points, const py::object& type) {
            return sim::Layout::of(sim::PointLayout::of(point_type_from(type), max_points));
          },
          py::arg("max_points"), py::arg("type") = "lidar_point",
          "Up to max_points points; frames read as a structured array (LIDAR_POINT_DTYPE for lidar_point).")
      .def_property_readonly("kind", [](const sim::Layout& l) { return l.kind; })
      .def_property_readonly("width", [](const sim::Layout& l) { return l.image.width; })
      .def_property_readonly("height", [](const sim::Layout& l) { return l.image.height; })
      .def_property_readonly("channels", [](const sim::Layout& l) { return l.image.channels; })
      .def_property_readonly("stride", [](const sim::Layout& l) { return l.image.stride; })
      .def_property_readonly("format", [](const sim::Layout& l) { return l.image.format; })
      .def_property_readonly("bit_depth", [](const sim::Layout& l) { return l.image.bit_depth; })
      .def_property_readonly("point_type", [](const sim::Layout& l) { return l.points.type; })
      .def_property_readonly("point_size", [](const sim::Layout& l) { return l.points.point_size; })
      .def_property_readonly("max_points", [](const sim::Layout& l) { return l.points.max_points; })
      .def_property_readonly("min_capacity", &sim::Layout::min_capacity,
                             "Bytes of the largest frame the layout describes (0 for raw/MJPEG).")
      .def_property_readonly(
          "dtype",
          [](const sim::Layout& l) -> py::object {
            if (l.kind == sim::LayoutKind::points) return point_dtype(l.points.type);
            if (l.kind == sim::LayoutKind::image && l.image.bit_depth > 8) return py::dtype("<u2");
            return py::dtype("u1");
          },
          "The numpy dtype of the stream's frames.")
      .def("describe", &sim::Layout::describe)
      .def("__repr__", [](const sim::Layout& l) { return "<sim.Layout " + l.describe() + ">"; })
      .def(py::self == py::self);
}

// What a reader learns about a frame: FrameInfo, ReaderStats.
void bind_frame_info(py::module_& m) {
  py::class_<sim::FrameInfo>(m, "FrameInfo", "What the writer said about a frame.")
      .def_readonly("seq", &sim::FrameInfo::seq, "Frame number; 1 for the first frame of the stream.")
      .def_readonly("stamp_ns", &sim::FrameInfo::stamp_ns, "Sensor time of the frame (CLOCK_REALTIME, ns).")
      .def_readonly("publish_ns", &sim::FrameInfo::publish_ns, "When it was published (CLOCK_MONOTONIC, ns).")
      .def_readonly("receive_ns", &sim::FrameInfo::receive_ns,
                    "When the host received its first data (CLOCK_REALTIME, ns); 0 if not given.")
      .def_readonly("size", &sim::FrameInfo::size, "Bytes.")
      .def_readonly("layout", &sim::FrameInfo::layout)
      .def_readonly("sensor_generation", &sim::FrameInfo::sensor_generation,
                    "0 when the stream has no sensor description, else a number that changes whenever the "
                    "writer sets one: read Reader.sensor_info again when it changed.")
      .def_readonly("clock_generation", &sim::FrameInfo::clock_generation,
                    "0 when the stream has no clock record, else a number that changes whenever the "
                    "writer sets one: read Reader.clock again when it changed.")
      .def_readonly("stamp_clock", &sim::FrameInfo::stamp_clock, "The clock stamp_ns is in (StampClock).")
      .def("as_dict", &info_to_dict)
      .def("__repr__", [](const sim::FrameInfo& i) {
        return "<sim.FrameInfo seq=" + std::to_string(i.seq) + " size=" + std::to_string(i.size) +
               " stamp_ns=" + std::to_string(i.stamp_ns) + ">";
      });

  py::class_<sim::ReaderStats>(m, "ReaderStats", "Counters of one reader.")
      .def_readonly("frames", &sim::ReaderStats::frames)
      .def_readonly("skipped", &sim::ReaderStats::skipped)
      .def_readonly("overruns", &sim::ReaderStats::overruns)
      .def_readonly("checksum_failures", &sim::ReaderStats::checksum_failures)
      .def_readonly("reopens", &sim::ReaderStats::reopens);
}

// Frame (a copy) and Borrow (in place): what a read returns.
void bind_frames(py::module_& m) {
  py::class_<FrameObject>(m, "Frame", "A copied frame: `array` (numpy, yours to keep) and `info`. Unpacks as (array, info).")
      .def_readonly("array", &FrameObject::array)
      .def_readonly("info", &FrameObject::info)
      .def("__iter__", [](const FrameObject& f) { return py::iter(py::make_tuple(f.array, f.info)); });

  py::class_<BorrowObject>(m, "Borrow",
                           "A frame read in place (zero-copy). Its `array` is a read-only view into shared "
                           "memory that keeps the mapping alive; the writer may overwrite the frame two "
                           "frames later, so check still_valid() after using the data.")
      .def_property_readonly(
          "array",
          [](py::object self) {
            const auto& b = self.cast<const BorrowObject&>();
            return shaped_array(b.info().layout, b.borrow().bytes().data(), b.borrow().bytes().size(),
                                self, false);
          },
          "A read-only numpy view of the frame (each access gives a new view of the same memory).")
      .def_property_readonly("info", &BorrowObject::info)
      .def("still_valid", &BorrowObject::still_valid,
           "True while the writer has not begun to overwrite the frame; call it after using the data.");
}

// Reader: reads one stream.
void bind_reader(py::module_& m) {
  py::class_<ReaderObject>(m, "Reader", "Reads one stream: copies (read, read_next) or borrows in place.")
      .def(py::init<const std::string&, double, bool, const std::string&, const std::string&>(),
           py::arg("name"), py::kw_only(), py::arg("stale_after") = 0.0, py::arg("verify_checksum") = true,
           py::arg("trust_owner") = "", py::arg("trust_group") = "",
           "Opens the stream `name` (\"/camera_front\"). By default only streams of this user are accepted; "
           "trust_owner / trust_group (a name or numeric id) accept that user's or group's streams. "
           "Raises SimError with the reason when it cannot.")
      .def("read", &ReaderObject::read,
           "The newest frame as a Frame (a copy) if it is newer than the last one returned, else None "
           "(last_status says why).")
      .def("read_next", &ReaderObject::read_next, py::arg("timeout"),
           "Waits up to `timeout` seconds (None: forever; the GIL is released) for a new frame, then read().")
      .def("wait", &ReaderObject::wait, py::arg("timeout"),
           "Waits up to `timeout` seconds for a new frame without reading it; True if there is one.")
      .def("borrow", &ReaderObject::borrow,
           "The newest frame in place as a Borrow if it is newer than the last one returned, else None.")
      .def("writer_alive", &ReaderObject::writer_alive, "Whether a process holds the stream's writer lock.")
      .def("close", &ReaderObject::close,
           "Closes the reader; borrowed views stay readable until they are deleted.")
      .def_property_readonly("closed", &ReaderObject::closed)
      .def_property_readonly("last_status", &ReaderObject::last_status)
      .def_property_readonly("name", &ReaderObject::name)
      .def_property_readonly("capacity", &ReaderObject::capacity)
      .def_property_readonly("layout", &ReaderObject::layout)
      .def_property_readonly("stats", &ReaderObject::stats)
      .def_property_readonly("sensor_info", &ReaderObject::sensor_info,
                             "The stream's SensorInfo (a copy), or None when it has none. Raises SimError "
                             "when the description in the stream is damaged (frames still flow).")
      .def_property_readonly("clock", &ReaderObject::clock,
                             "The stream's ClockStatus (a copy), or None when it has none yet. Raises "
                             "SimError when the record in the stream is damaged (frames still flow).")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](ReaderObject& r, py::args) { r.close(); });
}

// Loan and Writer: publish into one stream.
void bind_writer(py::module_& m) {
  py::class_<LoanObject>(m, "Loan",
                         "The writer's back slot, to fill in place; commit() publishes it. Its `array` "
                         "views must not be written after commit().")
      .def_property_readonly(
          "array", [](py::object self) { return self.cast<const LoanObject&>().array(self); },
          "A writable numpy view of the whole slot, shaped by the stream's layout.")
      .def_property_readonly("capacity", &LoanObject::capacity)
      .def("commit", &LoanObject::commit, py::arg("nbytes") = py::none(), py::kw_only(),
           py::arg("stamp_ns") = py::none(), py::arg("receive_ns") = 0,
           "Publishes the first `nbytes` bytes (default: a full frame of the layout). stamp_ns defaults to now.");

  py::class_<WriterObject>(m, "Writer", "The one writer of a stream.")
      .def(py::init<const std::string&, const sim::Layout&, std::uint64_t, bool, std::uint32_t, double,
                    std::optional<sim::SensorInfo>>(),
           py::arg("name"), py::arg("layout") = sim::Layout::raw(), py::kw_only(), py::arg("capacity") = 0,
           py::arg("checksum") = false, py::arg("mode") = 0600, py::arg("heartbeat_period") = 0.0,
           py::arg("sensor") = py::none(),
           "Creates (or takes over) the stream `name`. capacity 0 takes the layout's frame size; `sensor` "
           "(a SensorInfo) describes the stream's sensor.")
      .def("set_sensor_info", &WriterObject::set_sensor_info, py::arg("info"),
           "Replaces the stream's sensor description (a recalibration); SimError when it is invalid.")
      .def("set_clock", &WriterObject::set_clock, py::arg("clock"),
           "Replaces the stream's clock record (a ClockStatus); SimError when it is invalid.")
      .def("write", &WriterObject::write, py::arg("frame"), py::kw_only(), py::arg("stamp_ns") = py::none(),
           py::arg("receive_ns") = 0,
           "Copies a C-contiguous buffer (numpy array, bytes) in and publishes it. stamp_ns defaults to now.")
      .def("loan", &WriterObject::loan, "The back slot to fill in place (see Loan).")
      .def("close", &WriterObject::close, "Gives up the stream (once no loan is alive).")
      .def_property_readonly("closed", &WriterObject::closed)
      .def_property_readonly("name", &WriterObject::name)
      .def_property_readonly("capacity", &WriterObject::capacity)
      .def_property_readonly("layout", &WriterObject::layout)
      .def_property_readonly("last_seq", &WriterObject::last_seq)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](WriterObject& w, py::args) { w.close(); });
}

// The module's functions and constants.
void bind_functions(py::module_& m) {
  m.def("list_streams", &sim::list_streams, "Names of every SIM stream on this machine, sorted.");
  m.def(
      "destroy", [](const std::string& name, bool force) { raise_if_error(sim::destroy(name, force)); },
      py::arg("name"), py::kw_only(), py::arg("force") = false,
      "Removes a stream. Refused while its writer is alive unless force=True.");
  m.attr("LIDAR_POINT_DTYPE") = point_dtype(sim::PointType::lidar_point);
}

}  // namespace

PYBIND11_MODULE(_sim, m) {
  m.doc() = "SIM (Sensor-in-Memory): camera and LiDAR frames between processes through shared memory.";
  bind_errors(m);
  bind_enums(m);
  bind_layout(m);
  bind_frame_info(m);
  bind_frames(m);
  bind_reader(m);
  bind_writer(m);
  bind_sensor_info(m);
  bind_clock(m);
  bind_functions(m);
}
