// SPDX-License-Identifier: Apache-2.0
// The V4L2 driver above the system-call seam, against the in-memory fake device, writing into
// real SIM regions that a sim::Reader reads back: negotiation, every decode path, timestamps,
// drops, unplug and reconnect, corrupt input, and the tool's answer to a missing device.
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <thread>

#include "fake_v4l2_device.hpp"
#include "camera_options.hpp"
#include "sim/camera/v4l2_capture.hpp"
#include "sim/clock.hpp"
#include "sim/reader.hpp"
#include "test_images.hpp"

namespace sim::camera {
namespace {

using namespace std::chrono_literals;
using testing::Bytes;
using testing::FakeControl;
using testing::FakeFormat;
using testing::FakeFrame;
using testing::FakeV4l2Device;

constexpr const char* kPath = "/dev/video-fake";
const FourCc kYuyv = FourCc::of('Y', 'U', 'Y', 'V');
const FourCc kUyvy = FourCc::of('U', 'Y', 'V', 'Y');
const FourCc kMjpg = FourCc::of('M', 'J', 'P', 'G');
const FourCc kGrey = FourCc::of('G', 'R', 'E', 'Y');
const FourCc kY16 = FourCc::of('Y', '1', '6', ' ');

std::string unique_stream() {
  static int counter = 0;
  return "/test_camera_" + std::to_string(getpid()) + "_" + std::to_string(counter++);
}

// A UVC-like camera: YUYV only slowly at the large size, MJPEG fast at every size.
std::vector<FakeFormat> uvc_formats() {
  return {
      {kYuyv, "YUYV 4:2:2", {{64, 48}, {160, 120}, {320, 240}}, {30, 15}},
      {kMjpg, "Motion-JPEG", {{64, 48}, {160, 120}, {320, 240}}, {60, 30}},
      {kUyvy, "UYVY 4:2:2", {{64, 48}}, {30}},
      {kGrey, "8-bit Greyscale", {{64, 48}}, {30}},
      {kY16, "16-bit Greyscale", {{64, 48}}, {30}},
  };
}

std::vector<FakeControl> uvc_controls() {
  FakeControl brightness{V4L2_CID_BRIGHTNESS, "Brightness", V4L2_CTRL_TYPE_INTEGER, 0, 255, 1,
                         128, 128, {}};
  FakeControl exposure{V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", V4L2_CTRL_TYPE_MENU, 0, 3, 1, 3,
                       3, {"Auto Mode", "Manual Mode", "Shutter Priority Mode",
                           "Aperture Priority Mode"}};
  FakeControl exposure_time{V4L2_CID_EXPOSURE_ABSOLUTE, "Exposure Time, Absolute",
                            V4L2_CTRL_TYPE_INTEGER, 3, 2047, 1, 250, 250, {}};
  return {brightness, exposure, exposure_time};
}

class V4l2CaptureTest : public ::testing::Test {
 protected:
  V4l2CaptureTest() : fake(kPath, uvc_formats(), uvc_controls()) {
    config.device = kPath;
    config.stream = unique_stream();
    config.retry_period = 0ms;
    config.frame_timeout = 60s;
  }
  ~V4l2CaptureTest() override { (void)sim::destroy(config.stream, true); }

  Expected<V4l2Capture> start() { return V4l2Capture::start(fake, config); }

  // Steps until the fake has delivered everything it was given (bounded, never hangs).
  void drain(V4l2Capture& capture) {
    for (int i = 0; i < 100 && fake.pending() > 0; ++i) capture.step(10ms);
  }

  Reader open_reader(ReaderOptions options = {}) {
    auto reader = Reader::open(config.stream, options);
    EXPECT_TRUE(reader) << reader.error().message;
    return std::move(reader.value());
  }

  FakeV4l2Device fake;
  V4l2CaptureConfig config;
};

// --- negotiation ---------------------------------------------------------------------------

TEST_F(V4l2CaptureTest, AutoPrefersYuyvAndKeepsTheRequestedSize) {
  config.format.width = 160;
  config.format.height = 120;
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  EXPECT_EQ(capture->format().fourcc, kYuyv);
  EXPECT_EQ(fake.fourcc(), kYuyv);
  EXPECT_EQ(fake.width(), 160u);
  EXPECT_EQ(capture->output_layout(), imaging::make_layout(160, 120, PixelFormat::bgr8));
  EXPECT_TRUE(fake.streaming());
  EXPECT_EQ(fake.buffer_count(), 4u);
  EXPECT_EQ(fake.queued_buffers(), 4u);
  auto reader = open_reader();
  EXPECT_EQ(reader.layout(), Layout::of(imaging::make_layout(160, 120, PixelFormat::bgr8)));
}

TEST_F(V4l2CaptureTest, AutoTakesMjpegWhenOnlyItReachesTheRate) {
  config.format.width = 320;
  config.format.height = 240;
  config.format.fps = 60;
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  EXPECT_EQ(capture->format().fourcc, kMjpg);
  EXPECT_DOUBLE_EQ(capture->format().fps, 60.0);
  EXPECT_EQ(fake.fps(), 60u);
}

TEST_F(V4l2CaptureTest, AutoPrefersGreyForMonoOutput) {
  config.format.output = imaging::OutputFormat::mono8;
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  EXPECT_EQ(capture->format().fourcc, kGrey);
}

TEST_F(V4l2CaptureTest, UnsupportedSizeGetsTheClosestOne) {
  config.format.width = 300;
  config.format.height = 250;
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  EXPECT_EQ(capture->output_layout().width, 320u);
  EXPECT_EQ(capture->output_layout().height, 240u);
}

TEST_F(V4l2CaptureTest, AFormatTheDeviceLacksIsAClearError) {
  config.format.fourcc = FourCc::of('H', '2', '6', '4');
  auto capture = start();
  ASSERT_FALSE(capture);
  EXPECT_NE(capture.error().message.find("does not offer format H264"), std::string::npos)
      << capture.error().message;
  EXPECT_EQ(fake.open_handles(), 0);
}

TEST_F(V4l2CaptureTest, AMissingDeviceIsAClearError) {
  config.device = "/dev/video-none";
  auto capture = start();
  ASSERT_FALSE(capture);
  EXPECT_EQ(capture.error().code, ErrorCode::not_found);
  EXPECT_NE(capture.error().message.find("no video device at /dev/video-none"), std::string::npos);
}

TEST_F(V4l2CaptureTest, ListsFormatsAndControls) {
  auto device = V4l2Device::open(fake, kPath);
  ASSERT_TRUE(device);
  EXPECT_EQ(device->card(), "SIM fake camera");
  const auto formats = device->formats();
  ASSERT_EQ(formats.size(), 5u);
  EXPECT_EQ(formats[1].fourcc.str(), "MJPG");
  EXPECT_TRUE(formats[1].compressed);
  ASSERT_EQ(formats[0].sizes.size(), 3u);
  EXPECT_EQ(formats[0].sizes[2].width, 320u);
  EXPECT_EQ(formats[0].sizes[2].fps, (std::vector<double>{30, 15}));
  const auto controls = device->controls();
  ASSERT_EQ(controls.size(), 3u);
  EXPECT_EQ(controls[0].key, "brightness");
  EXPECT_EQ(controls[2].key, "exposure_time_absolute");
  EXPECT_EQ(controls[1].menu.size(), 4u);
}

TEST_F(V4l2CaptureTest, ControlsBySpelledNameNumberOrMenuEntry) {
  config.controls = {{"brightness", "200"}, {"Auto Exposure", "manual_mode"},
                     {"exposure_time_absolute", "100"}};
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  EXPECT_EQ(fake.control(V4L2_CID_BRIGHTNESS), 200);
  EXPECT_EQ(fake.control(V4L2_CID_EXPOSURE_AUTO), 1);
  EXPECT_EQ(fake.control(V4L2_CID_EXPOSURE_ABSOLUTE), 100);

  auto device = V4l2Device::open(fake, kPath);
  ASSERT_TRUE(device);
  auto unknown = device->set_control("focus", "3");
  ASSERT_TRUE(unknown);
  EXPECT_NE(unknown->message.find("--list-controls"), std::string::npos);
  auto range = device->set_control("brightness", "300");
  ASSERT_TRUE(range);
  EXPECT_NE(range->message.find("0 to 255"), std::string::npos);
  EXPECT_TRUE(device->set_control("brightness", "bright"));
  EXPECT_EQ(fake.control(V4L2_CID_BRIGHTNESS), 200);
}

// --- each decode path, through a real region --------------------------------------------

struct PathCase {
  FourCc fourcc;
  imaging::OutputFormat output;
  std::uint32_t row_padding;
};

class V4l2DecodePath : public V4l2CaptureTest,
                       public ::testing::WithParamInterface<PathCase> {};

TEST_P(V4l2DecodePath, ReaderGetsOpenCvsConversion) {
  const PathCase c = GetParam();
  config.format.fourcc = c.fourcc;
  config.format.width = 64;
  config.format.height = 48;
  config.format.output = c.output;
  fake.set_row_padding(c.row_padding);
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  const ImageLayout input = capture->format().layout;
  EXPECT_EQ(input.stride, imaging::row_bytes(64, input.format) + c.row_padding);

  const Bytes frame = c.fourcc == kMjpg
                          ? testing::encode_jpeg(testing::scene_bgr(64, 48, 4), 64, 48)
                          : testing::noise(input.frame_bytes(), 11);
  fake.push_frame({frame});
  ASSERT_EQ(capture->step(100ms), StepResult::published);

  auto reader = open_reader();
  Bytes got(reader.capacity());
  FrameInfo info;
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  EXPECT_EQ(info.layout.image, capture->output_layout());
  got.resize(info.size);
  if (c.output == imaging::OutputFormat::raw) {
    EXPECT_EQ(got, frame);
    EXPECT_EQ(info.layout.image.format, input.format);
  } else {
    const Bytes expected = testing::reference(input, frame, c.output);
    ASSERT_FALSE(expected.empty());
    EXPECT_LE(testing::max_difference(got, expected), c.fourcc == kMjpg ? 1 : 0);
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryFormat, V4l2DecodePath,
    ::testing::Values(PathCase{kYuyv, imaging::OutputFormat::bgr8, 0}, PathCase{kYuyv, imaging::OutputFormat::rgb8, 64},
                      PathCase{kYuyv, imaging::OutputFormat::mono8, 0}, PathCase{kYuyv, imaging::OutputFormat::raw, 32},
                      PathCase{kUyvy, imaging::OutputFormat::bgr8, 0}, PathCase{kMjpg, imaging::OutputFormat::bgr8, 0},
                      PathCase{kMjpg, imaging::OutputFormat::rgb8, 0}, PathCase{kMjpg, imaging::OutputFormat::mono8, 0},
                      PathCase{kMjpg, imaging::OutputFormat::raw, 0}, PathCase{kGrey, imaging::OutputFormat::mono8, 16},
                      PathCase{kGrey, imaging::OutputFormat::bgr8, 0}, PathCase{kY16, imaging::OutputFormat::mono8, 0}));

// --- timestamps and sequence ----------------------------------------------------------------

TEST_F(V4l2CaptureTest, DeviceTimestampIsMappedToRealtime) {
  config.format.width = 64;
  config.format.height = 48;
  config.time_offset_ns = 1'000;
  auto capture = start();
  ASSERT_TRUE(capture);
  // An exposure that started 250 ms ago on the monotonic clock.
  const std::int64_t exposure = monotonic_ns() - 250'000'000;
  const std::int64_t offset = realtime_ns() - monotonic_ns();
  fake.push_frame({testing::noise(64 * 48 * 2, 1), 0, false, exposure});
  ASSERT_EQ(capture->step(100ms), StepResult::published);
  auto reader = open_reader();
  Bytes got(reader.capacity());
  FrameInfo info;
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  // The mapping, not the time of publishing: 250 ms in the past (the clocks' offset can only
  // move by an NTP slew between two reads a few microseconds apart).
  EXPECT_NEAR(static_cast<double>(info.stamp_ns),
              static_cast<double>(exposure + offset + 1'000), 5e6);
  EXPECT_LT(info.stamp_ns, realtime_ns() - 200'000'000);
}

TEST_F(V4l2CaptureTest, ReceiveTimestampsIgnoreTheDeviceClock) {
  config.format.width = 64;
  config.format.height = 48;
  config.timestamps = TimestampSource::receive;
  auto capture = start();
  ASSERT_TRUE(capture);
  const std::int64_t before = realtime_ns();
  fake.push_frame({testing::noise(64 * 48 * 2, 1), 0, false, 12345});
  ASSERT_EQ(capture->step(100ms), StepResult::published);
  auto reader = open_reader();
  Bytes got(reader.capacity());
  FrameInfo info;
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  EXPECT_GE(info.stamp_ns, before);
  EXPECT_LE(info.stamp_ns, realtime_ns());
}

// --- the clock of the stamps ----------------------------------------------------------------

// UVC and most capture drivers stamp with CLOCK_MONOTONIC: the host's clock, mapped per frame.
TEST_F(V4l2CaptureTest, TheReportedClockSaysTheStampsAreTheBuffersOnTheHostsClock) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  // What a clock reporter takes, called from its own thread.
  const std::function<ClockStatus()> clock = capture->reported_clock();
  EXPECT_EQ(clock().source, ClockSource::host);
  EXPECT_EQ(clock().reported_ns, 0);  // no frame yet
  const std::int64_t before = realtime_ns();
  fake.push_frame({testing::noise(64 * 48 * 2, 1), 0, false, -1});
  ASSERT_EQ(capture->step(100ms), StepResult::published);
  const ClockStatus now = clock();
  EXPECT_EQ(now.source, ClockSource::host);
  EXPECT_EQ(now.state, ClockState::unknown);  // the host's own synchronisation is judged apart
  EXPECT_EQ(now.stamps, StampClock::sensor);
  EXPECT_EQ(now.verdict, ClockVerdict::unknown) << now.problem;
  EXPECT_GE(now.reported_ns, before);
}

// A buffer without a monotonic stamp cannot be mapped: the frame carries the receive time, and
// the clock record says so, for UNKNOWN, COPY and a value V4L2 does not define; a monotonic
// buffer afterwards clears the warning at once.
TEST_F(V4l2CaptureTest, AnUnknownOrCopiedBufferClockIsAWarningAndTheFramesCarryTheReceiveTime) {
  config.format.width = 64;
  config.format.height = 48;
  std::vector<std::string> logged;
  config.log = [&logged](std::string_view line) { logged.emplace_back(line); };
  auto capture = start();
  ASSERT_TRUE(capture);
  const ReportedClock clock = capture->reported_clock();
  auto reader = open_reader();
  Bytes got(reader.capacity());
  struct Case {
    std::uint32_t flags;
    const char* named;
  };
  for (const Case c : {Case{V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN, "TIMESTAMP_UNKNOWN"},
                       Case{V4L2_BUF_FLAG_TIMESTAMP_COPY | V4L2_BUF_FLAG_TSTAMP_SRC_SOE, "TIMESTAMP_COPY"},
                       Case{V4L2_BUF_FLAG_TIMESTAMP_MASK, "TIMESTAMP_UNKNOWN"}}) {
    const std::int64_t before = realtime_ns();
    FakeFrame frame{testing::noise(64 * 48 * 2, 1), 0, false, 12345};
    frame.timestamp_flags = c.flags;
    fake.push_frame(frame);
    ASSERT_EQ(capture->step(100ms), StepResult::published);
    FrameInfo info;
    ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
    EXPECT_GE(info.stamp_ns, before);  // the receive time, not 12 µs after boot
    EXPECT_LE(info.stamp_ns, realtime_ns());
    const ClockStatus now = clock();
    EXPECT_EQ(now.source, ClockSource::host);
    EXPECT_EQ(now.stamps, StampClock::host_arrival);
    EXPECT_EQ(now.verdict, ClockVerdict::warn);
    EXPECT_NE(now.problem.find(c.named), std::string::npos) << now.problem;
  }
  fake.push_frame({testing::noise(64 * 48 * 2, 1), 0, false, -1});
  ASSERT_EQ(capture->step(100ms), StepResult::published);
  EXPECT_EQ(clock().stamps, StampClock::sensor);
  EXPECT_EQ(clock().verdict, ClockVerdict::unknown) << clock().problem;
  // Each change to a clock that cannot be mapped is said once in the log, not per frame.
  ASSERT_EQ(logged.size(), 3U);
  EXPECT_EQ(logged[1].rfind("warning: ", 0), 0U) << logged[1];
  EXPECT_NE(logged[1].find("TIMESTAMP_COPY"), std::string::npos) << logged[1];
}

// The clock check writes the stream's clock record about once a second while frames come: a
// reader sees the V4L2 clock (host, the buffers' stamps) with the frames measured against their
// arrival, judged with the camera's tolerance.
TEST_F(V4l2CaptureTest, TheStreamsClockRecordFollowsTheFramesAsTheyCome) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  auto reader = open_reader();
  std::optional<ClockStatus> record;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  // From the first frame on the record says which clock the stamps are in; the judgement (the
  // frames measured) follows within about a second.
  while ((!record || record->packets_measured == 0) && std::chrono::steady_clock::now() < deadline) {
    fake.push_frame({testing::noise(64 * 48 * 2, 1), 0, false, -1});
    ASSERT_EQ(capture->step(100ms), StepResult::published);
    std::this_thread::sleep_for(20ms);
    auto clock = reader.clock();
    ASSERT_TRUE(clock) << clock.error().message;
    ASSERT_TRUE(*clock) << "a frame was published before the stream's first clock record";
    EXPECT_EQ((*clock)->stamps, StampClock::sensor);
    record = *clock;
  }
  ASSERT_TRUE(record) << "no clock record within a minute of frames";
  EXPECT_EQ(record->source, ClockSource::host);
  EXPECT_EQ(record->stamps, StampClock::sensor);
  EXPECT_GT(record->packets_measured, 0U);
  ASSERT_TRUE(record->offset_to_host_ns);
  // A buffer stamped at its dequeue (the fake's "now") lies well within a camera's tolerance.
  EXPECT_LT(std::llabs(*record->offset_to_host_ns), camera_clock_tolerance().offset_ok_ns);
}

TEST_F(V4l2CaptureTest, ReceiveTimestampsReportTheHostsArrivalWhateverTheBuffersSay) {
  config.format.width = 64;
  config.format.height = 48;
  config.timestamps = TimestampSource::receive;
  auto capture = start();
  ASSERT_TRUE(capture);
  FakeFrame frame{testing::noise(64 * 48 * 2, 1), 0, false, 12345};
  frame.timestamp_flags = V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN;
  fake.push_frame(frame);
  ASSERT_EQ(capture->step(100ms), StepResult::published);
  const ClockStatus now = capture->reported_clock()();
  EXPECT_EQ(now.source, ClockSource::host);
  EXPECT_EQ(now.stamps, StampClock::host_arrival);
  EXPECT_EQ(now.verdict, ClockVerdict::unknown) << now.problem;  // asked for: nothing wrong
}

TEST_F(V4l2CaptureTest, SequenceGapsCountDroppedFrames) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  const Bytes frame = testing::noise(64 * 48 * 2, 1);
  fake.push_frame({frame});
  fake.push_frame({frame, 3});  // three frames lost in the device
  fake.push_frame({frame});
  fake.push_frame({frame, 1});
  drain(*capture);
  EXPECT_EQ(capture->stats().published, 4u);
  EXPECT_EQ(capture->stats().dropped, 4u);
}

// --- bad input -------------------------------------------------------------------------------

TEST_F(V4l2CaptureTest, CorruptAndMisfitFramesAreCountedAndNeverPublished) {
  config.format.fourcc = kMjpg;
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  auto reader = open_reader();
  Bytes got(reader.capacity());
  FrameInfo info;

  const Bytes good = testing::encode_jpeg(testing::scene_bgr(64, 48, 1), 64, 48);
  const Bytes truncated(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(good.size() / 2));
  fake.push_frame({truncated});
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  fake.push_frame({testing::noise(3000, 4)});
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  fake.push_frame({testing::encode_jpeg(testing::scene_bgr(160, 120, 1), 160, 120)});
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  fake.push_frame({good, 0, true});  // the device flagged the buffer as bad
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  fake.push_frame({{}});  // bytesused 0
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  EXPECT_EQ(reader.read(got, info), ReadStatus::no_new_frame);

  fake.push_frame({good});
  EXPECT_EQ(capture->step(100ms), StepResult::published);
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 1u);
  EXPECT_EQ(capture->stats().corrupt, 3u);
  EXPECT_EQ(capture->stats().bad_size, 1u);
  EXPECT_EQ(capture->stats().device_errors, 1u);
  EXPECT_EQ(capture->stats().published, 1u);
}

TEST_F(V4l2CaptureTest, ShortUncompressedFramesAreSkipped) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  fake.push_frame({testing::noise(64 * 48 * 2 - 2, 1)});
  EXPECT_EQ(capture->step(100ms), StepResult::skipped);
  EXPECT_EQ(capture->stats().bad_size, 1u);
  EXPECT_EQ(capture->stats().published, 0u);
}

TEST_F(V4l2CaptureTest, EagainAndStallsAreNotErrors) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  fake.push_error(EAGAIN);
  EXPECT_EQ(capture->step(100ms), StepResult::no_frame);
  fake.push_stall();
  EXPECT_EQ(capture->step(100ms), StepResult::no_frame);
  fake.push_frame({testing::noise(64 * 48 * 2, 1)});
  EXPECT_EQ(capture->step(100ms), StepResult::published);
  EXPECT_EQ(capture->stats().device_losses, 0u);
}

TEST_F(V4l2CaptureTest, AStalledStreamIsRestarted) {
  config.format.width = 64;
  config.format.height = 48;
  config.frame_timeout = 0ms;
  auto capture = start();
  ASSERT_TRUE(capture);
  fake.push_stall();
  EXPECT_EQ(capture->step(100ms), StepResult::device_lost);
  EXPECT_EQ(capture->stats().timeouts, 1u);
  EXPECT_EQ(capture->step(100ms), StepResult::reconnected);
  EXPECT_EQ(fake.opens(), 2);
  EXPECT_TRUE(fake.streaming());
}

// --- unplug and reconnect --------------------------------------------------------------------

TEST_F(V4l2CaptureTest, UnplugKeepsTheStreamAndResumesOnReplug) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  const Bytes frame = testing::noise(64 * 48 * 2, 1);
  fake.push_frame({frame});
  ASSERT_EQ(capture->step(100ms), StepResult::published);

  ReaderOptions options;
  options.stale_after = 1ms;
  auto reader = open_reader(options);
  Bytes got(reader.capacity());
  FrameInfo info;
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 1u);

  fake.push_error(ENODEV);  // DQBUF: the camera is gone
  EXPECT_EQ(capture->step(100ms), StepResult::device_lost);
  EXPECT_FALSE(capture->connected());
  EXPECT_EQ(fake.open_handles(), 0);  // the dead handle was closed…
  EXPECT_EQ(fake.mapped_buffers(), 0);  // …and its buffers unmapped
  EXPECT_EQ(capture->step(10ms), StepResult::disconnected);

  // The region is still there; readers see it go stale, not vanish.
  std::this_thread::sleep_for(5ms);
  EXPECT_EQ(reader.read(got, info), ReadStatus::stale);
  auto late_reader = Reader::open(config.stream);
  EXPECT_TRUE(late_reader);

  fake.plug();
  EXPECT_EQ(capture->step(100ms), StepResult::reconnected);
  fake.push_frame({frame});
  EXPECT_EQ(capture->step(100ms), StepResult::published);
  ASSERT_EQ(reader.read(got, info), ReadStatus::new_frame);
  EXPECT_EQ(info.seq, 2u);  // same stream, same sequence
  EXPECT_EQ(capture->stats().device_losses, 1u);
  EXPECT_EQ(capture->stats().reconnects, 1u);
}

TEST_F(V4l2CaptureTest, PollErrorAndEioAreUnplugsToo) {
  config.format.width = 64;
  config.format.height = 48;
  auto capture = start();
  ASSERT_TRUE(capture);
  fake.unplug();  // poll reports POLLERR
  EXPECT_EQ(capture->step(100ms), StepResult::device_lost);
  fake.plug();
  EXPECT_EQ(capture->step(100ms), StepResult::reconnected);
  fake.push_error(EIO);
  EXPECT_EQ(capture->step(100ms), StepResult::device_lost);
  EXPECT_EQ(capture->step(100ms), StepResult::reconnected);
  fake.push_frame({testing::noise(64 * 48 * 2, 2)});
  EXPECT_EQ(capture->step(100ms), StepResult::published);
  EXPECT_EQ(capture->stats().device_losses, 2u);
}

TEST_F(V4l2CaptureTest, StoppingReleasesEverything) {
  config.format.width = 64;
  config.format.height = 48;
  {
    auto capture = start();
    ASSERT_TRUE(capture);
    EXPECT_EQ(fake.mapped_buffers(), 4);
  }
  EXPECT_EQ(fake.open_handles(), 0);
  EXPECT_EQ(fake.mapped_buffers(), 0);
  EXPECT_FALSE(fake.streaming());
}

// --- configuration file and tool --------------------------------------------------------------

// Parses a camera program's command line (the program name first) as the tool would.
template <typename Options, typename Add, typename Finish>
std::optional<int> parse_options(std::vector<std::string> words, Options& options, Add add,
                                 Finish finish) {
  sim::apps::CommandLine cli("sim_camera_test", "test");
  add(cli, options);
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  if (auto code = cli.parse(static_cast<int>(argv.size()), argv.data())) return code;
  if (auto problem = finish(options)) return cli.usage_error(*problem);
  return std::nullopt;
}

std::optional<int> parse_v4l2(std::vector<std::string> words, V4l2Options& options) {
  return parse_options(std::move(words), options, add_v4l2_options, finish_v4l2_options);
}

// A camera's exposure and transfer put its stamps tens of milliseconds before their arrival:
// the clock check's tolerance for cameras is wider than a LiDAR's, and an option.
TEST(V4l2Config, TheClockToleranceIsACamerasByDefaultAndAnOption) {
  const timing::ClockTolerance lidar;
  V4l2Options defaults;
  EXPECT_FALSE(parse_v4l2({"t"}, defaults));
  EXPECT_EQ(defaults.clock.tolerance.offset_ok_ns, 250'000'000);
  EXPECT_GT(defaults.clock.tolerance.offset_ok_ns, lidar.offset_ok_ns);
  EXPECT_GT(defaults.clock.tolerance.spread_warn_ns, lidar.spread_warn_ns);
  EXPECT_EQ(defaults.clock.tolerance.offset_error_ns, lidar.offset_error_ns);
  V4l2Options wider;
  EXPECT_FALSE(parse_v4l2({"t", "--clock-offset-ok-ms", "400", "--clock-spread-warn-ms", "80.5"}, wider));
  EXPECT_EQ(wider.clock.tolerance.offset_ok_ns, 400'000'000);
  EXPECT_EQ(wider.clock.tolerance.spread_warn_ns, 80'500'000);
  V4l2Options too_wide;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse_v4l2({"t", "--clock-offset-ok-ms", "5000"}, too_wide), std::optional<int>(2));
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("--clock-offset-ok-ms"), std::string::npos);
}

TEST(V4l2Config, YamlFillsTheConfigUnderTheCommandLineAndRefusesBadKeys) {
  const std::string path = "/tmp/test_camera_config_" + std::to_string(getpid()) + ".yaml";
  {
    FILE* file = std::fopen(path.c_str(), "w");
    ASSERT_NE(file, nullptr);
    std::fputs("device: /dev/video3\nstream: /cam_left\nformat: MJPG\nwidth: 1280\nheight: 720\n"
               "fps: 30\noutput: rgb8\ncontrols:\n  brightness: 100\n  exposure_auto: 1\n"
               "cpu: 1\ntimestamps: receive\n",
               file);
    std::fclose(file);
  }
  V4l2Options options;
  EXPECT_FALSE(parse_v4l2({"t", "--config", path, "--width", "640"}, options));
  const V4l2CaptureConfig& config = options.config;
  EXPECT_EQ(config.device, "/dev/video3");
  EXPECT_EQ(config.stream, "/cam_left");
  EXPECT_EQ(config.format.fourcc, FourCc::of('M', 'J', 'P', 'G'));
  EXPECT_EQ(config.format.width, 640u);  // the command line wins
  EXPECT_EQ(config.format.height, 720u);
  EXPECT_EQ(config.format.output, imaging::OutputFormat::rgb8);
  ASSERT_EQ(config.controls.size(), 2u);
  EXPECT_EQ(config.controls[1].key, "exposure_auto");
  EXPECT_EQ(options.placement.cpu, 1);
  EXPECT_EQ(config.timestamps, TimestampSource::receive);

  {
    FILE* file = std::fopen(path.c_str(), "w");
    std::fputs("widht: 640\n", file);
    std::fclose(file);
  }
  V4l2Options typo;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse_v4l2({"t", "--config", path}, typo), std::optional<int>(2));
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("widht"), std::string::npos);
  {
    FILE* file = std::fopen(path.c_str(), "w");
    std::fputs("width: wide\n", file);
    std::fclose(file);
  }
  V4l2Options wrong_type;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse_v4l2({"t", "--config", path}, wrong_type), std::optional<int>(2));
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("width"), std::string::npos);
  std::remove(path.c_str());
  V4l2Options missing;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse_v4l2({"t", "--config", path}, missing), std::optional<int>(2));
  ::testing::internal::GetCapturedStderr();
}

TEST(CameraConfig, ShippedExamplesParse) {
  V4l2Options v4l2;
  EXPECT_FALSE(parse_v4l2({"t", "--config", std::string(SIM_CAMERA_CONFIG_DIR) + "/v4l2_usb.yaml"},
                          v4l2));
  EXPECT_EQ(v4l2.config.format.width, 1280u);
  EXPECT_EQ(v4l2.config.controls.size(), 3u);

  AravisOptions aravis;
  EXPECT_FALSE(parse_options(
      {"t", "--config", std::string(SIM_CAMERA_CONFIG_DIR) + "/aravis_gige.yaml"}, aravis,
      add_aravis_options, finish_aravis_options));
  EXPECT_EQ(aravis.config.pixel_format, "BayerRG8");
  EXPECT_EQ(aravis.config.width, 1920);
  EXPECT_TRUE(aravis.config.packet_socket);
  ASSERT_EQ(aravis.config.features.size(), 2u);
  EXPECT_EQ(aravis.config.features[0].first, "ExposureAuto");
  EXPECT_EQ(aravis.config.features[0].second, "Off");
}

// Opt-in, for developer machines with a camera: SIM_CAMERA_DEVICE=/dev/video0 runs the real
// libv4l2 path (this project's CI kernels have no V4L2).
TEST(V4l2RealDevice, CapturesFramesWhenADeviceIsGiven) {
  const char* path = std::getenv("SIM_CAMERA_DEVICE");
  if (path == nullptr) GTEST_SKIP() << "set SIM_CAMERA_DEVICE=/dev/videoN to test a real camera";
  const auto io = make_libv4l2_io();
  V4l2CaptureConfig config;
  config.device = path;
  config.stream = unique_stream();
  auto capture = V4l2Capture::start(*io, config);
  ASSERT_TRUE(capture) << capture.error().message;
  for (int i = 0; i < 200 && capture->stats().published < 10; ++i) capture->step(100ms);
  EXPECT_GE(capture->stats().published, 10u);
  (void)sim::destroy(config.stream, true);
}

struct ToolRun {
  int exit_code = -1;
  std::string output;
};

ToolRun run_tool(const std::string& arguments) {
  ToolRun run;
  const std::string command = std::string(SIM_CAMERA_V4L2_TOOL) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 512> chunk{};
  while (std::fgets(chunk.data(), chunk.size(), pipe) != nullptr) run.output += chunk.data();
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

TEST(V4l2Tool, MissingDeviceFailsWithOneSentence) {
  const ToolRun run = run_tool("/dev/video-sim-missing --stream " + unique_stream());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("no video device at /dev/video-sim-missing"), std::string::npos)
      << run.output;
  const ToolRun list = run_tool("/dev/video-sim-missing --list-formats");
  EXPECT_EQ(list.exit_code, 1);
}

TEST(V4l2Tool, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run_tool("--output bgr").exit_code, 2);
  EXPECT_EQ(run_tool("--ctrl brightness").exit_code, 2);
  EXPECT_EQ(run_tool("--format TOOLONG").exit_code, 2);
  const ToolRun help = run_tool("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--list-controls"), std::string::npos);
}

}  // namespace
}  // namespace sim::camera

// --- the stream's sensor description (issue 21) --------------------------------------------

namespace sim::camera {
namespace {

sim::CameraCalibration calibration_of(std::uint32_t width, std::uint32_t height) {
  sim::CameraCalibration c;
  c.width = width;
  c.height = height;
  c.camera_name = "front";
  c.d = {-0.28, 0.07, 0.0004, -0.0003, 0.0};
  c.k = {200.5, 0, 80.25, 0, 201.0, 60.5, 0, 0, 1};
  c.p = {200.5, 0, 80.25, 0, 0, 201.0, 60.5, 0, 0, 0, 1, 0};
  return c;
}

TEST_F(V4l2CaptureTest, TheStreamCarriesTheCalibrationMountingCardAndBus) {
  config.format.width = 160;
  config.format.height = 120;
  sim::SensorInfo sensor;
  sensor.frame_id = "camera_front_optical";
  sensor.mounting = sim::Mounting::from_xyz_rpy(1.5, 0, 1.2, -1.5707963, 0, -1.5707963);
  sensor.calibration = calibration_of(160, 120);
  config.sensor = sensor;
  auto capture = start();
  ASSERT_TRUE(capture) << capture.error().message;
  Reader reader = open_reader();
  auto info = reader.sensor_info();
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  const sim::SensorInfo& s = **info;
  EXPECT_EQ(s.frame_id, "camera_front_optical");
  EXPECT_EQ(s.mounting, sensor.mounting);
  ASSERT_TRUE(s.calibration.has_value());
  EXPECT_TRUE(*s.calibration == calibration_of(160, 120));
  EXPECT_EQ(s.identity.model, "SIM fake camera");
  EXPECT_EQ(s.identity.serial, "platform:simfake-0");
  EXPECT_EQ(s.time_base, sim::TimeBase::host);
  EXPECT_EQ(s.point_time, sim::PointTime::none);
}

TEST_F(V4l2CaptureTest, ACalibrationOfAnotherSizeIsRefusedAndNoStreamIsCreated) {
  config.format.width = 160;
  config.format.height = 120;
  sim::SensorInfo sensor;
  sensor.frame_id = "camera_front_optical";
  sensor.calibration = calibration_of(640, 480);
  config.sensor = sensor;
  auto capture = start();
  ASSERT_FALSE(capture);
  EXPECT_EQ(capture.error().code, sim::ErrorCode::invalid_argument);  // exit 2 in the program
  EXPECT_NE(capture.error().message.find("640x480"), std::string::npos) << capture.error().message;
  EXPECT_NE(capture.error().message.find("160x120"), std::string::npos) << capture.error().message;
  auto reader = Reader::open(config.stream);
  ASSERT_FALSE(reader);
  EXPECT_EQ(reader.error().code, sim::ErrorCode::not_found);
}

}  // namespace
}  // namespace sim::camera
