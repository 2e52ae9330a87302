// SPDX-License-Identifier: Apache-2.0
// sim_camera_aravis in its own process against Aravis's GigE Vision fake camera hosted by this
// test on 127.0.0.1: the real GVCP/GVSP path over UDP. Everything runs in a private network
// namespace (discovery broadcasts never leave it). Checks size, format and pixel content of the
// published frames, and that killing the camera leads to a reconnect, not an exit. The camera's
// clock as the capture reports it: the stock fake camera has no PTP features (its clock is
// reported as what it is), a fake with the SFNC PTP features added to its GenICam XML shows each
// PTP state the camera goes through.
#include <arv.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "sim/camera/aravis_capture.hpp"
#include "sim/sim.hpp"
#include "sim_test/network.hpp"

namespace {

using namespace std::chrono_literals;

// Set in main(): why this process has no private network (its tests then skip).
std::optional<std::string> g_skip_reason;

// Mono8: a pattern each pixel can be checked against. BayerRG8: a pure red scene.
void fill(ArvBuffer* buffer, void* data, guint32, guint32, ArvPixelFormat format) {
  auto* camera = static_cast<ArvFakeCamera*>(data);
  guint32 width = 0;
  guint32 height = 0;
  arv_fake_camera_read_register(camera, ARV_FAKE_CAMERA_REGISTER_WIDTH, &width);
  arv_fake_camera_read_register(camera, ARV_FAKE_CAMERA_REGISTER_HEIGHT, &height);
  // arv_buffer_get_data reports size 0 here in 0.8.26: the payload is width × height × 1 byte.
  auto* pixels = static_cast<guint8*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
  for (guint32 y = 0; y < height; ++y) {
    for (guint32 x = 0; x < width; ++x) {
      guint8 value = 0;
      if (format == ARV_PIXEL_FORMAT_BAYER_RG_8) {
        value = (x % 2 == 0 && y % 2 == 0) ? 255 : 0;
      } else {
        value = static_cast<guint8>((x * 3 + y * 5) & 0xff);
      }
      pixels[y * width + x] = value;
    }
  }
}

class FakeGvCamera {
 public:
  // `genicam`: the camera's GenICam XML file; empty: Aravis's own.
  explicit FakeGvCamera(const char* serial, const std::string& genicam = {}) {
    camera_ = genicam.empty() ? arv_gv_fake_camera_new("127.0.0.1", serial)
                              : arv_gv_fake_camera_new_full("127.0.0.1", serial, genicam.c_str());
    if (camera_ != nullptr) {
      ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(camera_);
      arv_fake_camera_set_fill_pattern(fake, fill, fake);
    }
  }
  ~FakeGvCamera() {
    if (camera_ != nullptr) g_object_unref(camera_);
  }
  bool running() const { return camera_ != nullptr && arv_gv_fake_camera_is_running(camera_); }
  ArvFakeCamera* fake() const { return arv_gv_fake_camera_get_fake_camera(camera_); }

 private:
  ArvGvFakeCamera* camera_ = nullptr;
};

class AravisDriver : public ::testing::Test {
 protected:
  void SetUp() override {
    if (g_skip_reason) GTEST_SKIP() << *g_skip_reason;
    static int counter = 0;
    stream = "/test_camera_aravis_" + std::to_string(getpid()) + "_" + std::to_string(counter++);
    log = "/tmp" + stream + ".log";
  }
  void TearDown() override {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    (void)sim::destroy(stream, true);
    std::remove(log.c_str());
  }

  void spawn(std::vector<std::string> args) {
    args.insert(args.begin(), SIM_CAMERA_ARAVIS_TOOL);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDERR_FILENO, STDOUT_FILENO);
    ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
  }

  int wait_exit(std::chrono::seconds limit = 30s) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    int status = 0;
    while (waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
        pid = -1;
        return -1;
      }
      std::this_thread::sleep_for(10ms);
    }
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  std::string output() const {
    std::ifstream file(log);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  }

  std::optional<sim::Reader> open_reader() {
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    while (std::chrono::steady_clock::now() < deadline) {
      auto reader = sim::Reader::open(stream);
      if (reader) return std::move(reader.value());
      std::this_thread::sleep_for(10ms);
    }
    return std::nullopt;
  }

  // The next frame within `limit`, copied into `buffer`.
  bool next_frame(sim::Reader& reader, std::vector<std::byte>& buffer, sim::FrameInfo& info,
                  std::chrono::seconds limit = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      if (reader.read_next(buffer, info, 200ms) == sim::ReadStatus::new_frame) return true;
    }
    return false;
  }

  std::string stream;
  std::string log;
  pid_t pid = -1;
};

TEST_F(AravisDriver, Mono8FramesArriveWithTheirSizeAndPixels) {
  FakeGvCamera camera("SIMMONO");
  ASSERT_TRUE(camera.running());
  spawn({"127.0.0.1", "--stream", stream, "--pixel-format", "Mono8", "--output", "mono8", "--roi",
         "0", "0", "128", "96", "--fps", "20", "-q"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  const sim::ImageLayout& layout = reader->layout().image;
  EXPECT_EQ(layout.width, 128u);
  EXPECT_EQ(layout.height, 96u);
  EXPECT_EQ(layout.format, sim::PixelFormat::mono8);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  for (int frame = 0; frame < 3; ++frame) {
    ASSERT_TRUE(next_frame(*reader, buffer, info)) << output();
    ASSERT_EQ(info.size, 128u * 96u);
    for (std::uint32_t y = 0; y < 96; ++y) {
      for (std::uint32_t x = 0; x < 128; ++x) {
        ASSERT_EQ(static_cast<int>(buffer[y * 128 + x]), static_cast<int>((x * 3 + y * 5) & 0xff))
            << "pixel " << x << "," << y;
      }
    }
    // Host receive time by default: close to now on CLOCK_REALTIME.
    EXPECT_LT(std::llabs(info.stamp_ns - sim::realtime_ns()), 5'000'000'000LL);
  }
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();
  // -q: no status line redrawn in place.
  EXPECT_EQ(output().find("\r"), std::string::npos) << output();
}

TEST_F(AravisDriver, BayerRg8IsDebayeredToTheRightColour) {
  FakeGvCamera camera("SIMBAYER");
  ASSERT_TRUE(camera.running());
  spawn({"127.0.0.1", "--stream", stream, "--pixel-format", "BayerRG8", "--output", "bgr8", "--roi",
         "0", "0", "64", "48", "--fps", "20", "-q"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  EXPECT_EQ(reader->layout().image.format, sim::PixelFormat::bgr8);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_TRUE(next_frame(*reader, buffer, info)) << output();
  const std::size_t centre = (24 * 64 + 32) * 3;
  EXPECT_EQ(static_cast<int>(buffer[centre + 0]), 0);    // B
  EXPECT_EQ(static_cast<int>(buffer[centre + 1]), 0);    // G
  EXPECT_EQ(static_cast<int>(buffer[centre + 2]), 255);  // R
}

TEST_F(AravisDriver, LosingTheCameraLeadsToAReconnectNotAnExit) {
  std::optional<FakeGvCamera> camera;
  camera.emplace("SIMLOST");
  ASSERT_TRUE(camera->running());
  spawn({"127.0.0.1", "--stream", stream, "--output", "mono8", "--roi", "0", "0", "64", "48",
         "--fps", "20", "-q"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_TRUE(next_frame(*reader, buffer, info)) << output();
  const std::uint64_t before = info.seq;

  camera.reset();  // the camera disappears: no heartbeat answers, no frames
  std::this_thread::sleep_for(1s);
  (void)reader->read(buffer, info);  // drain a frame that was in flight
  camera.emplace("SIMLOST");
  ASSERT_TRUE(camera->running());
  // Aravis notices the lost control after its heartbeat timeout (about 5 s), then the driver
  // reopens the camera; the stream and its sequence continue.
  ASSERT_TRUE(next_frame(*reader, buffer, info, 40s)) << output();
  EXPECT_GT(info.seq, before);
  EXPECT_TRUE(reader->writer_alive());
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();
  EXPECT_NE(output().find("reconnected"), std::string::npos) << output();
}

TEST_F(AravisDriver, YamlConfigWithGenicamFeatures) {
  FakeGvCamera camera("SIMYAML");
  ASSERT_TRUE(camera.running());
  const std::string config = "/tmp" + stream + ".yaml";
  {
    std::ofstream file(config);
    file << "device: 127.0.0.1\npixel_format: Mono8\noutput: bgr8\nroi: [0, 0, 80, 60]\n"
            "features:\n  AcquisitionFrameRate: 25\n";
  }
  // The command line overrides the file's output.
  spawn({"--config", config, "--stream", stream, "--output", "mono8", "-q"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  EXPECT_EQ(reader->layout().image.width, 80u);
  EXPECT_EQ(reader->layout().image.format, sim::PixelFormat::mono8);
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();

  {
    std::ofstream file(config);
    file << "device: 127.0.0.1\nfeatures:\n  NoSuchFeature: 1\n";
  }
  spawn({"--config", config, "--stream", stream, "-q"});
  EXPECT_EQ(wait_exit(), 1) << output();
  EXPECT_NE(output().find("no GenICam feature 'NoSuchFeature'"), std::string::npos) << output();
  std::remove(config.c_str());
}

TEST_F(AravisDriver, AMissingCameraIsOneSentenceAndExitOne) {
  spawn({"SIM-NO-SUCH-CAMERA", "--stream", stream, "-q"});
  EXPECT_EQ(wait_exit(), 1) << output();
  EXPECT_NE(output().find("no camera 'SIM-NO-SUCH-CAMERA'"), std::string::npos) << output();
  spawn({"--roi", "1", "2"});
  EXPECT_EQ(wait_exit(), 2);
}


// --- the camera's clock ----------------------------------------------------------------------

// Where the PTP features added to the fake camera keep their values: a free part of its memory,
// above the bootstrap and the fake's own registers.
constexpr guint32 kPtpEnable = 0x8000;
constexpr guint32 kPtpStatus = 0x8004;  // 1 Initializing … 9 Slave, the SFNC order
constexpr guint32 kPtpServo = 0x8008;   // 0 Unknown, 1 Locked
constexpr guint32 kPtpLatch = 0x800c;
constexpr guint32 kPtpOffset = 0x8010;       // 8 bytes, signed, ns
constexpr guint32 kPtpGrandmaster = 0x8018;  // 8 bytes

std::string int_reg(const std::string& name, guint32 address, int length, const char* sign) {
  char text[400];
  std::snprintf(text, sizeof text,
                "<IntReg Name=\"%s\" NameSpace=\"Custom\"><Address>0x%x</Address><Length>%d</Length>"
                "<AccessMode>RW</AccessMode><pPort>Device</pPort><Cachable>NoCache</Cachable><Sign>%s</Sign>"
                "<Endianess>BigEndian</Endianess></IntReg>\n",
                name.c_str(), address, length, sign);
  return text;
}

// The SFNC PTP features as a PTP camera's GenICam XML names them.
std::string ptp_features() {
  std::string xml =
      "<Boolean Name=\"PtpEnable\" NameSpace=\"Standard\"><pValue>PtpEnableRegister</pValue>"
      "<OnValue>1</OnValue><OffValue>0</OffValue></Boolean>\n"
      "<Enumeration Name=\"PtpStatus\" NameSpace=\"Standard\">";
  const char* states[] = {"Initializing", "Faulty",  "Disabled",     "Listening", "PreMaster",
                          "Master",       "Passive", "Uncalibrated", "Slave"};
  for (int i = 0; i < 9; ++i) {
    xml += "<EnumEntry Name=\"" + std::string(states[i]) + "\" NameSpace=\"Standard\"><Value>" +
           std::to_string(i + 1) + "</Value></EnumEntry>";
  }
  xml += "<pValue>PtpStatusRegister</pValue></Enumeration>\n"
         "<Enumeration Name=\"PtpServoStatus\" NameSpace=\"Standard\">"
         "<EnumEntry Name=\"Unknown\" NameSpace=\"Standard\"><Value>0</Value></EnumEntry>"
         "<EnumEntry Name=\"Locked\" NameSpace=\"Standard\"><Value>1</Value></EnumEntry>"
         "<pValue>PtpServoStatusRegister</pValue></Enumeration>\n"
         "<Integer Name=\"PtpOffsetFromMaster\" NameSpace=\"Standard\"><pValue>PtpOffsetRegister</pValue></Integer>\n"
         "<Integer Name=\"PtpGrandmasterClockID\" NameSpace=\"Standard\">"
         "<pValue>PtpGrandmasterRegister</pValue></Integer>\n"
         "<Command Name=\"PtpDataSetLatch\" NameSpace=\"Standard\"><pValue>PtpLatchRegister</pValue>"
         "<CommandValue>1</CommandValue></Command>\n";
  xml += int_reg("PtpEnableRegister", kPtpEnable, 4, "Unsigned");
  xml += int_reg("PtpStatusRegister", kPtpStatus, 4, "Unsigned");
  xml += int_reg("PtpServoStatusRegister", kPtpServo, 4, "Unsigned");
  xml += int_reg("PtpLatchRegister", kPtpLatch, 4, "Unsigned");
  xml += int_reg("PtpOffsetRegister", kPtpOffset, 8, "Signed");
  xml += int_reg("PtpGrandmasterRegister", kPtpGrandmaster, 8, "Unsigned");
  return xml;
}

// Aravis's own fake camera XML with the PTP features added, written to `path` (the project
// keeps no copy of Aravis's XML).
std::string write_ptp_genicam(const std::string& path) {
  ArvFakeCamera* plain = arv_fake_camera_new("PLAIN");
  size_t size = 0;
  const char* text = arv_fake_camera_get_genicam_xml(plain, &size);
  std::string xml(text != nullptr ? text : "", text != nullptr ? size : 0);
  g_object_unref(plain);
  const auto end = xml.rfind("</RegisterDescription>");
  if (end == std::string::npos) return {};
  xml.insert(end, ptp_features());
  std::ofstream(path) << xml;
  return path;
}

// A big-endian register of the fake camera, as the GenICam XML reads it.
void set_register(ArvFakeCamera* camera, guint32 address, std::uint64_t value, int length = 4) {
  std::uint8_t bytes[8];
  for (int i = 0; i < length; ++i) bytes[i] = static_cast<std::uint8_t>(value >> (8 * (length - 1 - i)));
  ASSERT_TRUE(arv_fake_camera_write_memory(camera, address, static_cast<guint32>(length), bytes));
}

// AravisCapture in this process (its clock accessor is what a clock reporter calls), run on a
// thread until the test ends, with a reader of its stream.
struct InProcessCapture {
  std::optional<sim::camera::AravisCapture> capture;
  std::atomic<bool> stop{false};
  std::thread thread;

  std::string start(sim::camera::AravisCaptureConfig config) {
    auto started = sim::camera::AravisCapture::start(std::move(config));
    if (!started) return started.error().message;
    capture.emplace(std::move(started.value()));
    thread = std::thread([this] { capture->run(stop); });
    return {};
  }
  ~InProcessCapture() {
    stop.store(true);
    if (thread.joinable()) thread.join();
  }
};

sim::camera::AravisCaptureConfig clock_test_config(const std::string& stream) {
  sim::camera::AravisCaptureConfig config;
  config.device_id = "127.0.0.1";
  config.stream = stream;
  config.pixel_format = "Mono8";
  config.output = sim::imaging::OutputFormat::mono8;
  config.width = 64;
  config.height = 48;
  config.fps = 20;
  return config;
}

// Waits (bounded) until `clock` satisfies `reached`.
bool clock_reaches(const std::function<sim::ClockStatus()>& clock,
                   const std::function<bool(const sim::ClockStatus&)>& reached) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!reached(clock()) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(20ms);
  return reached(clock());
}

// Aravis's fake camera has no PTP feature: its frames carry the host receive time, and the
// clock says exactly that, read again about once a second while frames keep coming.
TEST_F(AravisDriver, TheFakeCamerasClockIsReportedAsTheHostReceiveTimeWhileFramesFlow) {
  FakeGvCamera camera("SIMCLOCK");
  ASSERT_TRUE(camera.running());
  InProcessCapture run;
  ASSERT_EQ(run.start(clock_test_config(stream)), "");
  const std::function<sim::ClockStatus()> clock = run.capture->reported_clock();
  const sim::ClockStatus first = clock();
  EXPECT_EQ(first.source, sim::ClockSource::host);
  EXPECT_EQ(first.state, sim::ClockState::unknown);  // the host's own synchronisation is judged apart
  EXPECT_EQ(first.stamps, sim::StampClock::host_arrival);
  EXPECT_EQ(first.verdict, sim::ClockVerdict::unknown) << first.problem;
  EXPECT_GT(first.reported_ns, 0);  // read when the camera was opened
  ASSERT_TRUE(clock_reaches(clock, [&](const sim::ClockStatus& c) { return c.reported_ns > first.reported_ns; }));
  auto reader = open_reader();
  ASSERT_TRUE(reader);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(next_frame(*reader, buffer, info));
  EXPECT_EQ(clock().source, sim::ClockSource::host);
}

// Asked for the camera's own clock, which no PTP disciplines: free-running, with the reason.
TEST_F(AravisDriver, TheCamerasOwnClockWithoutPtpIsReportedFreeRunningWithTheReason) {
  FakeGvCamera camera("SIMFREE");
  ASSERT_TRUE(camera.running());
  auto config = clock_test_config(stream);
  config.device_timestamps = true;
  InProcessCapture run;
  ASSERT_EQ(run.start(config), "");
  const sim::ClockStatus clock = run.capture->reported_clock()();
  EXPECT_EQ(clock.source, sim::ClockSource::free_running);
  EXPECT_EQ(clock.state, sim::ClockState::free_running);
  EXPECT_EQ(clock.stamps, sim::StampClock::sensor);
  EXPECT_EQ(clock.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(clock.problem.find("no PTP features"), std::string::npos) << clock.problem;
  auto reader = open_reader();
  ASSERT_TRUE(reader);
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_TRUE(next_frame(*reader, buffer, info));
}

// A camera with the SFNC PTP features: each state it goes through reaches the clock accessor
// within about a second, read through the GenICam control channel while frames flow.
TEST_F(AravisDriver, EachPtpStateOfTheCameraReachesTheClockAccessor) {
  const std::string genicam = write_ptp_genicam(log + ".xml");
  ASSERT_FALSE(genicam.empty());
  FakeGvCamera camera("SIMPTP", genicam);
  ASSERT_TRUE(camera.running());
  set_register(camera.fake(), kPtpEnable, 1);
  set_register(camera.fake(), kPtpStatus, 4);  // Listening
  InProcessCapture run;
  ASSERT_EQ(run.start(clock_test_config(stream)), "");
  std::remove(genicam.c_str());
  const std::function<sim::ClockStatus()> clock = run.capture->reported_clock();
  sim::ClockStatus now = clock();
  EXPECT_EQ(now.source, sim::ClockSource::ptp);
  EXPECT_EQ(now.state, sim::ClockState::acquiring);
  EXPECT_EQ(now.stamps, sim::StampClock::sensor);  // PTP on: the camera's clock stamps the frames
  EXPECT_EQ(now.verdict, sim::ClockVerdict::warn);
  EXPECT_NE(now.problem.find("Listening"), std::string::npos) << now.problem;

  // Locked to a master: offset and grandmaster as the camera reports them.
  set_register(camera.fake(), kPtpOffset, static_cast<std::uint64_t>(std::int64_t{-1234}), 8);
  set_register(camera.fake(), kPtpGrandmaster, 0x001122fffe334455ULL, 8);
  set_register(camera.fake(), kPtpServo, 1);
  set_register(camera.fake(), kPtpStatus, 9);  // Slave
  ASSERT_TRUE(clock_reaches(clock, [](const sim::ClockStatus& c) { return c.state == sim::ClockState::locked; }))
      << clock().problem;
  now = clock();
  EXPECT_EQ(now.offset_from_master_ns, -1234);
  EXPECT_EQ(now.grandmaster, "001122.fffe.334455");
  EXPECT_EQ(now.verdict, sim::ClockVerdict::unknown) << now.problem;
  // The stream's clock record, as the clock check writes it about once a second, says the same.
  auto reader = open_reader();
  ASSERT_TRUE(reader);
  const std::function<sim::ClockStatus()> record = [&reader] {
    auto c = reader->clock();
    return c && c->has_value() ? **c : sim::ClockStatus{};
  };
  // Judged (frames measured), not the record before the first judgement, which names the stamps only.
  ASSERT_TRUE(clock_reaches(record, [](const sim::ClockStatus& c) {
    return c.state == sim::ClockState::locked && c.packets_measured > 0;
  }))
      << sim::summary(record());
  EXPECT_EQ(record().source, sim::ClockSource::ptp);
  EXPECT_EQ(record().grandmaster, "001122.fffe.334455");
  EXPECT_GT(record().packets_measured, 0U);

  // The servo loses its lock, then the port goes faulty, then the camera becomes the master.
  set_register(camera.fake(), kPtpServo, 0);
  ASSERT_TRUE(clock_reaches(clock, [](const sim::ClockStatus& c) { return c.state == sim::ClockState::acquiring; }));
  set_register(camera.fake(), kPtpStatus, 2);  // Faulty
  ASSERT_TRUE(clock_reaches(clock, [](const sim::ClockStatus& c) { return c.state == sim::ClockState::holdover; }));
  set_register(camera.fake(), kPtpStatus, 6);  // Master
  ASSERT_TRUE(clock_reaches(clock, [](const sim::ClockStatus& c) {
    return c.state == sim::ClockState::free_running && c.problem.find("master") != std::string::npos;
  })) << clock().problem;
  guint32 latched = 0;
  ASSERT_TRUE(arv_fake_camera_read_register(camera.fake(), kPtpLatch, &latched));
  EXPECT_NE(latched, 0U);  // the data set was latched before it was read

  // Frames kept flowing all along.
  std::vector<std::byte> buffer(reader->capacity());
  sim::FrameInfo info;
  ASSERT_TRUE(next_frame(*reader, buffer, info));
}

}  // namespace

// A 128x96 calibration in camera_calibration_parsers YAML, written by hand.
std::string write_calibration(const std::string& path, int width, int height) {
  std::ofstream(path) << "image_width: " << width << "\nimage_height: " << height
                      << "\ncamera_name: gige\ncamera_matrix: {rows: 3, cols: 3, data: [110.5, 0, "
                         "64, 0, 111, 48, 0, 0, 1]}\ndistortion_model: plumb_bob\n"
                         "distortion_coefficients: {rows: 1, cols: 5, data: [0.01, 0, 0, 0, 0]}\n"
                         "rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n"
                         "projection_matrix: {rows: 3, cols: 4, data: [110.5, 0, 64, 0, 0, 111, 48, 0, "
                         "0, 0, 1, 0]}\n";
  return path;
}

TEST_F(AravisDriver, TheStreamCarriesTheDeviceInfoTheClockAndTheCalibration) {
  FakeGvCamera camera("SIMINFO");
  ASSERT_TRUE(camera.running());
  const std::string yaml = write_calibration(log + ".yaml", 128, 96);
  spawn({"127.0.0.1", "--stream", stream, "--pixel-format", "Mono8", "--output", "mono8", "--roi",
         "0", "0", "128", "96", "--fps", "20", "-q", "--camera-info", yaml, "--frame-id",
         "gige_optical", "--parent-frame", "camera_mount", "--x", "0.1"});
  auto reader = open_reader();
  ASSERT_TRUE(reader) << output();
  auto info = reader->sensor_info();
  std::remove(yaml.c_str());
  ASSERT_TRUE(info) << info.error().message;
  ASSERT_TRUE(info->has_value());
  const sim::SensorInfo& s = **info;
  EXPECT_EQ(s.frame_id, "gige_optical");
  EXPECT_EQ(s.parent_frame, "camera_mount");
  ASSERT_TRUE(s.mounting.has_value());
  EXPECT_EQ(s.mounting->translation[0], 0.1);
  ASSERT_TRUE(s.calibration.has_value());
  EXPECT_EQ(s.calibration->k[0], 110.5);
  // Aravis's fake camera names itself in its GenICam features.
  EXPECT_EQ(s.identity.vendor, "Aravis");
  EXPECT_FALSE(s.identity.model.empty());
  EXPECT_NE(s.identity.serial.find("SIMINFO"), std::string::npos) << s.identity.serial;
  // No PTP on the fake camera: host receive time, said so.
  EXPECT_EQ(s.time_base, sim::TimeBase::host);
  EXPECT_EQ(s.time_sync, "host receive time");
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_exit(), 0) << output();
}

TEST_F(AravisDriver, ACalibrationOfAnotherSizeIsExitTwoAndNoStream) {
  FakeGvCamera camera("SIMCAL");
  ASSERT_TRUE(camera.running());
  const std::string yaml = write_calibration(log + ".yaml", 640, 480);
  spawn({"127.0.0.1", "--stream", stream, "--pixel-format", "Mono8", "--output", "mono8", "--roi",
         "0", "0", "128", "96", "-q", "--camera-info", yaml});
  EXPECT_EQ(wait_exit(), 2) << output();
  std::remove(yaml.c_str());
  const std::string message = output();
  EXPECT_NE(message.find("640x480"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), message.size() - 1) << "one line: " << message;
  EXPECT_FALSE(sim::Reader::open(stream));
}

int main(int argc, char** argv) {
  g_skip_reason = sim::testing::enter_private_network(sim::testing::Multicast::off);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
