// SPDX-License-Identifier: Apache-2.0
// The host clock reader against a real ptp4l: a master and a slave in two private network
// namespaces joined by a veth pair, software timestamping, and free_running on both (network
// namespaces do not isolate CLOCK_REALTIME: a servo would step this machine's clock). Also: no
// ptp4l, a socket that never answers, and a socket that answers nonsense.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/timex.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sim/timing/host_clock.hpp"
#include "sim_test/process.hpp"

namespace {

using namespace std::chrono_literals;
using sim::ClockSource;
using sim::ClockState;
using sim::ClockVerdict;
using sim::testing::Process;
using sim::timing::HostClock;
using sim::timing::HostClockOptions;
using sim::timing::HostClockWatch;

constexpr auto kBound = 60s;  // against hangs only: every wait below ends long before

// A private folder for sockets and configuration, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "sim-host-clock.XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

std::string program(const std::string& name) {
  for (const char* dir : {"/usr/sbin", "/sbin", "/usr/bin", "/bin", "/usr/local/sbin"}) {
    const std::string path = std::string(dir) + "/" + name;
    if (::access(path.c_str(), X_OK) == 0) return path;
  }
  return {};
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// What real pmc says: the value after `field` in the answer to `get` (an independent check).
std::string pmc_field(const std::string& socket, const TempDir& dir, const std::string& get,
                      const std::string& field) {
  const auto run = sim::testing::run({program("pmc"), "-u", "-b", "0", "-s", socket, "-i",
                                      dir / "pmc", get});
  std::istringstream lines(run.out);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string name, value;
    if (words >> name >> value && name == field) return value;
  }
  return {};
}

// Two namespaces joined by a veth pair, each running ptp4l on its end; all removed on exit.
class PtpRig {
 public:
  // Why the rig cannot be built here (the test skips with it), or nothing.
  static std::optional<std::string> unavailable() {
    if (::geteuid() != 0) return "needs root for network namespaces";
    if (program("ptp4l").empty() || program("pmc").empty()) return "linuxptp is not installed";
    if (program("ip").empty()) return "iproute2 (ip) is not installed";
    return std::nullopt;
  }

  PtpRig() : tag_(std::to_string(::getpid())) {
    master_ns_ = "simhc" + tag_ + "m";
    slave_ns_ = "simhc" + tag_ + "s";
    const std::string master_if = "shm" + tag_, slave_if = "shs" + tag_;
    ok_ = ip({"netns", "add", master_ns_}) && ip({"netns", "add", slave_ns_}) &&
          ip({"link", "add", master_if, "netns", master_ns_, "type", "veth", "peer", "name",
              slave_if, "netns", slave_ns_}) &&
          ip({"-n", master_ns_, "link", "set", master_if, "up"}) &&
          ip({"-n", slave_ns_, "link", "set", slave_if, "up"});
    if (!ok_) return;
    write_config("master", "priority1 1\n");
    write_config("slave", "slaveOnly 1\n");
    master_ = start(master_ns_, master_if, "master");
    slave_ = start(slave_ns_, slave_if, "slave");
  }
  ~PtpRig() {
    master_.reset();
    slave_.reset();
    ip({"netns", "del", master_ns_});  // takes its end of the veth pair, and so the pair, along
    ip({"netns", "del", slave_ns_});
  }
  bool ok() const { return ok_; }
  std::string socket(const std::string& role) const { return dir_ / (role + ".sock"); }
  std::string log(const std::string& role) const { return file_text(dir_ / (role + ".log")); }
  const TempDir& dir() const { return dir_; }
  void stop_master() {
    ::kill(master_->pid(), SIGTERM);
    master_->wait();
  }

 private:
  bool ip(std::vector<std::string> args) {
    args.insert(args.begin(), program("ip"));
    const auto run = sim::testing::run(args);
    if (run.code != 0) error_ += run.err;
    return run.code == 0;
  }
  void write_config(const std::string& role, const std::string& extra) {
    // Fast announce and sync intervals keep the test short; free_running: NEVER adjust the clock.
    std::ofstream(dir_ / (role + ".cfg"))
        << "[global]\nfree_running 1\nuds_address " << socket(role)
        << "\nlogAnnounceInterval -3\nannounceReceiptTimeout 2\nlogSyncInterval -4\n"
           "logMinDelayReqInterval -4\nuse_syslog 0\nverbose 1\n"
        << extra;
  }
  std::unique_ptr<Process> start(const std::string& ns, const std::string& interface,
                                 const std::string& role) {
    // Output to a file: a pipe nobody reads would fill and stall ptp4l.
    const std::string command = "exec " + program("ip") + " netns exec " + ns + " " +
                                program("ptp4l") + " -2 -S -i " + interface + " -f " +
                                (dir_ / (role + ".cfg")) + " > " + (dir_ / (role + ".log")) +
                                " 2>&1";
    return std::make_unique<Process>(std::vector<std::string>{"/bin/sh", "-c", command});
  }

  TempDir dir_;
  std::string tag_, master_ns_, slave_ns_, error_;
  bool ok_ = false;
  std::unique_ptr<Process> master_, slave_;

 public:
  const std::string& error() const { return error_; }
};

// Reads until `done` holds for a reading (or the bound passes); the last reading.
template <typename Done>
HostClock read_until(const HostClockOptions& options, Done done) {
  const auto deadline = std::chrono::steady_clock::now() + kBound;
  HostClock reading = sim::timing::read_host_clock_details(options);
  while (!done(reading) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(50ms);
    reading = sim::timing::read_host_clock_details(options);
  }
  return reading;
}

// Log lines gathered from a HostClockWatch.
struct Lines {
  std::mutex mutex;
  std::vector<std::string> lines;
  std::vector<std::string> snapshot() {
    std::lock_guard lock(mutex);
    return lines;
  }
  std::size_t count(const std::string& needle) {
    std::size_t n = 0;
    for (const auto& line : snapshot()) n += line.find(needle) != std::string::npos;
    return n;
  }
};

TEST(HostClock, ASlavePtp4lNamesItsMastersIdentityAndNoticesTheMasterStopping) {
  if (auto why = PtpRig::unavailable()) GTEST_SKIP() << *why;
  PtpRig rig;
  if (!rig.ok()) GTEST_SKIP() << "cannot build the veth pair: " << rig.error();
  auto lines = std::make_shared<Lines>();
  sim::timing::HostClockWatchOptions watch_options;
  watch_options.clock.ptp4l_socket = rig.socket("slave");
  watch_options.period = 100ms;
  watch_options.log = [lines](const std::string& line) {
    std::lock_guard lock(lines->mutex);
    lines->lines.push_back(line);
  };
  HostClockWatch watch(watch_options);

  // The master's identity, as real pmc reads it from the master.
  std::string master_id;
  const auto deadline = std::chrono::steady_clock::now() + kBound;
  while (master_id.empty() && std::chrono::steady_clock::now() < deadline) {
    master_id = pmc_field(rig.socket("master"), rig.dir(), "GET DEFAULT_DATA_SET", "clockIdentity");
    if (master_id.empty()) std::this_thread::sleep_for(50ms);
  }
  ASSERT_EQ(master_id.size(), 18u) << rig.log("master");

  HostClockOptions options;
  options.ptp4l_socket = rig.socket("slave");
  const HostClock slave = read_until(options, [&](const HostClock& h) {
    return h.status.grandmaster == master_id && h.status.offset_from_master_ns.has_value() &&
           h.status.state != ClockState::unknown;
  });
  ASSERT_EQ(slave.status.grandmaster, master_id) << slave.description << "\n" << rig.log("slave");
  EXPECT_EQ(slave.status.source, ClockSource::ptp);
  EXPECT_EQ(slave.status.ptp_domain, 0);
  ASSERT_TRUE(slave.ptp4l && slave.ptp4l->ports.size() == 1u);
  // ptp4l's own port state, as ptp4l says it: with free_running its servo never locks, so the
  // port stays UNCALIBRATED (SLAVE would read as locked).
  const auto port = slave.ptp4l->ports[0].state;
  EXPECT_EQ(pmc_field(rig.socket("slave"), rig.dir(), "GET PORT_DATA_SET", "portState"),
            sim::timing::ptp::to_string(port));
  if (port == sim::timing::ptp::PortState::slave) {
    EXPECT_EQ(slave.status.state, ClockState::locked);
  } else {
    EXPECT_EQ(port, sim::timing::ptp::PortState::uncalibrated);
    EXPECT_EQ(slave.status.state, ClockState::acquiring);
    EXPECT_EQ(slave.status.verdict, ClockVerdict::warn);
    EXPECT_NE(slave.status.problem.find("UNCALIBRATED"), std::string::npos);
  }
  // Both ends read the same clock over a veth pair: a measured offset of a few µs, and a delay.
  ASSERT_TRUE(slave.status.offset_from_master_ns.has_value());
  EXPECT_LT(std::llabs(*slave.status.offset_from_master_ns), 1'000'000'000LL);
  EXPECT_TRUE(slave.status.path_delay_ns.has_value());
  EXPECT_GT(slave.status.reported_ns, 0);
  EXPECT_EQ(sim::clock_status_problem(slave.status), "");  // a writer can store it as it is

  // The watch logged the change from "no ptp4l" (it started before ptp4l's socket existed, or
  // while it was still listening) to the slave of the master, once.
  ASSERT_TRUE(watch.poller().wait_for_readings(watch.poller().readings() + 1, kBound));
  EXPECT_EQ(watch.latest().grandmaster, master_id);
  EXPECT_EQ(lines->count("grandmaster " + master_id + ", offset"), 1u) << ::testing::PrintToString(lines->snapshot());

  // The master stops: after the announce timeout the slave listens for another one.
  rig.stop_master();
  const HostClock alone = read_until(options, [&](const HostClock& h) {
    return h.ptp4l && !h.ptp4l->ports.empty() &&
           h.ptp4l->ports[0].state == sim::timing::ptp::PortState::listening;
  });
  ASSERT_TRUE(alone.ptp4l && !alone.ptp4l->ports.empty()) << alone.ptp4l_absent;
  EXPECT_EQ(alone.ptp4l->ports[0].state, sim::timing::ptp::PortState::listening) << rig.log("slave");
  EXPECT_EQ(alone.status.state, ClockState::acquiring);
  // ptp4l keeps the last grandmaster and offset; the offset is stale and not reported.
  EXPECT_FALSE(alone.status.offset_from_master_ns.has_value());
  // Several readings later, the change is still logged once, saying what it was before.
  const auto seen = watch.poller().readings();
  ASSERT_TRUE(watch.poller().wait_for_readings(seen + 3, kBound));
  const auto all = lines->snapshot();
  for (const auto& line : all) std::cout << line << '\n';  // what a user sees on stderr
  EXPECT_EQ(lines->count("ptp LISTENING, last grandmaster " + master_id), 1u) << ::testing::PrintToString(all);
  ASSERT_FALSE(all.empty());
  EXPECT_NE(all.back().find("(was: ptp UNCALIBRATED, grandmaster " + master_id), std::string::npos)
      << all.back();
  EXPECT_NE(all.back().find(" UTC"), std::string::npos) << all.back();
}

TEST(HostClock, WithoutPtp4lTheSourceIsTheHostInTheKernelsState) {
  TempDir dir;
  HostClockOptions options;
  options.ptp4l_socket = dir / "ptp4l";  // nothing there
  const HostClock host = sim::timing::read_host_clock_details(options);
  EXPECT_FALSE(host.ptp4l.has_value());
  EXPECT_NE(host.ptp4l_absent.find("no ptp4l socket at " + options.ptp4l_socket), std::string::npos);
  EXPECT_EQ(host.status.source, ClockSource::host);
  EXPECT_EQ(host.status.ptp_domain, -1);
  timex tx{};
  const int kernel = ::adjtimex(&tx);
  ASSERT_GE(kernel, 0);
  const bool unsynchronised = kernel == TIME_ERROR || (tx.status & STA_UNSYNC) != 0;
  EXPECT_EQ(host.status.state, unsynchronised ? ClockState::free_running : ClockState::locked);
  EXPECT_EQ(host.status.verdict, unsynchronised ? ClockVerdict::warn : ClockVerdict::ok);
  EXPECT_EQ(host.description.rfind("no ptp4l; the kernel says", 0), 0u) << host.description;
}

// A Unix datagram socket at `path` served by a thread: `answer` gets each request and returns
// the datagrams to send back.
class FakePtp4l {
 public:
  using Answer = std::function<std::vector<std::vector<std::uint8_t>>(const std::vector<std::uint8_t>&)>;
  FakePtp4l(const std::string& path, Answer answer) : answer_(std::move(answer)) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, path.c_str(), sizeof address.sun_path - 1);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      throw std::runtime_error("cannot bind " + path);
    }
    if (answer_) thread_ = std::thread([this] { serve(); });
  }
  ~FakePtp4l() {
    stop_ = true;
    ::shutdown(fd_, SHUT_RDWR);
    if (thread_.joinable()) thread_.join();
    ::close(fd_);
  }

 private:
  void serve() {
    std::array<std::uint8_t, 2048> buffer{};
    while (!stop_) {
      sockaddr_un from{};
      socklen_t length = sizeof from;
      timeval tv{0, 100'000};
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      const ssize_t got = ::recvfrom(fd_, buffer.data(), buffer.size(), 0,
                                     reinterpret_cast<sockaddr*>(&from), &length);
      if (got <= 0) continue;
      const std::vector<std::uint8_t> request(buffer.begin(), buffer.begin() + got);
      for (const auto& reply : answer_(request)) {
        ::sendto(fd_, reply.data(), reply.size(), 0, reinterpret_cast<const sockaddr*>(&from), length);
      }
    }
  }
  Answer answer_;
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(HostClock, ASocketThatNeverAnswersCostsItsBoundAndNoMore) {
  TempDir dir;
  FakePtp4l silent(dir / "ptp4l", nullptr);  // bound, never read
  HostClockOptions options;
  options.ptp4l_socket = dir / "ptp4l";
  options.ptp4l_timeout = 200ms;
  const auto start = std::chrono::steady_clock::now();
  const HostClock host = sim::timing::read_host_clock_details(options);
  // Not a timing check: a reader that waited on the socket would never return at all.
  EXPECT_LT(std::chrono::steady_clock::now() - start, 20s);
  EXPECT_FALSE(host.ptp4l.has_value());
  EXPECT_NE(host.ptp4l_absent.find("did not answer"), std::string::npos) << host.ptp4l_absent;
  EXPECT_EQ(host.status.source, ClockSource::host);
}

// A management RESPONSE as ptp4l sends it (built here, independently of the reader's encoder):
// the request's header with the action set to RESPONSE and `data` after the managementId.
std::vector<std::uint8_t> response_to(const std::vector<std::uint8_t>& request,
                                      const std::vector<std::uint8_t>& data) {
  const std::size_t tlv_length = 2 + data.size();
  std::vector<std::uint8_t> m(48 + 4 + tlv_length, 0);
  std::copy(request.begin(), request.begin() + 48, m.begin());
  m[46] = 2;  // RESPONSE
  m[49] = 0x01;  // MANAGEMENT
  m[50] = static_cast<std::uint8_t>(tlv_length >> 8);
  m[51] = static_cast<std::uint8_t>(tlv_length);
  m[52] = request[52];
  m[53] = request[53];
  std::copy(data.begin(), data.end(), m.begin() + 54);
  m[2] = static_cast<std::uint8_t>(m.size() >> 8);
  m[3] = static_cast<std::uint8_t>(m.size());
  return m;
}

std::uint16_t asked_id(const std::vector<std::uint8_t>& request) {
  return request.size() >= 54 ? static_cast<std::uint16_t>(request[52] << 8 | request[53]) : 0;
}

TEST(HostClock, AnAbsurdOffsetFromASlaveIsAWarningNotACrash) {
  TempDir dir;
  FakePtp4l liar(dir / "ptp4l", [](const std::vector<std::uint8_t>& request)
                                    -> std::vector<std::vector<std::uint8_t>> {
    if ((request[0] >> 4) != 0 || request[4] != 0) return {};  // domain 0, plain PTP
    switch (asked_id(request)) {
      case 0x2004: {  // PORT_DATA_SET: port 1 SLAVE
        std::vector<std::uint8_t> d(26, 0);
        d[9] = 1;
        d[10] = 9;
        return {response_to(request, d)};
      }
      case 0x2001: {  // CURRENT_DATA_SET: offsetFromMaster = 5000 s (× 2^16)
        std::vector<std::uint8_t> d(18, 0);
        const std::int64_t scaled = 5'000'000'000'000LL * 65536;
        for (int i = 0; i < 8; ++i) d[2 + i] = static_cast<std::uint8_t>(scaled >> (56 - 8 * i));
        return {response_to(request, d)};
      }
      default:
        return {};  // the rest unanswered
    }
  });
  HostClockOptions options;
  options.ptp4l_socket = dir / "ptp4l";
  const HostClock host = sim::timing::read_host_clock_details(options);
  ASSERT_TRUE(host.ptp4l.has_value()) << host.ptp4l_absent;
  EXPECT_EQ(host.status.source, ClockSource::ptp);
  EXPECT_EQ(host.status.state, ClockState::locked);  // what ptp4l says: SLAVE
  EXPECT_EQ(host.status.offset_from_master_ns, 5'000'000'000'000LL);
  EXPECT_EQ(host.status.verdict, ClockVerdict::warn);
  EXPECT_NE(host.status.problem.find("offset"), std::string::npos) << host.status.problem;
}

TEST(HostClock, AnswersCutShortAreAWarningWithTheirReason) {
  TempDir dir;
  FakePtp4l broken(dir / "ptp4l", [](const std::vector<std::uint8_t>& request)
                                      -> std::vector<std::vector<std::uint8_t>> {
    if ((request[0] >> 4) != 0) return {};
    auto whole = response_to(request, std::vector<std::uint8_t>(50, 0xFF));
    auto cut = whole;
    cut.resize(40);  // cut inside the header
    auto lying = whole;
    lying[3] = 0xF0;  // says it is longer than it is
    return {cut, lying, std::vector<std::uint8_t>{}};
  });
  HostClockOptions options;
  options.ptp4l_socket = dir / "ptp4l";
  const HostClock host = sim::timing::read_host_clock_details(options);
  ASSERT_TRUE(host.ptp4l.has_value()) << host.ptp4l_absent;
  EXPECT_EQ(host.status.state, ClockState::unknown);
  EXPECT_EQ(host.status.verdict, ClockVerdict::warn);
  EXPECT_NE(host.status.problem.find("cut short"), std::string::npos) << host.status.problem;
  EXPECT_EQ(sim::clock_status_problem(host.status), "");
}

TEST(HostClock, Ptp4lInAnotherDomainAndSpeaking8021ASIsFoundAndReadAsGptp) {
  TempDir dir;
  std::atomic<int> requests{0};
  // Answers only domain 7 with transportSpecific 1, as ptp4l with gPTP.cfg and domainNumber 7.
  FakePtp4l gptp(dir / "ptp4l", [&](const std::vector<std::uint8_t>& request)
                                    -> std::vector<std::vector<std::uint8_t>> {
    ++requests;
    if ((request[0] >> 4) != 1 || request[4] != 7) return {};
    if (asked_id(request) == 0x2000) {  // DEFAULT_DATA_SET: domainNumber 7
      std::vector<std::uint8_t> d(20, 0);
      d[18] = 7;
      return {response_to(request, d)};
    }
    if (asked_id(request) == 0x2004) {  // PORT_DATA_SET: port 1 SLAVE
      std::vector<std::uint8_t> d(26, 0);
      d[9] = 1;
      d[10] = 9;
      return {response_to(request, d)};
    }
    return {};
  });
  HostClockOptions options;
  options.ptp4l_socket = dir / "ptp4l";
  const HostClock found = sim::timing::read_host_clock_details(options);
  ASSERT_TRUE(found.ptp4l.has_value()) << found.ptp4l_absent;
  EXPECT_EQ(found.status.source, ClockSource::gptp);
  EXPECT_EQ(found.status.ptp_domain, 7);
  EXPECT_EQ(found.status.state, ClockState::locked);
  // The next reading asks the domain it learned: far fewer requests than a sweep.
  const int before = requests.load();
  const HostClock again = sim::timing::read_host_clock_details(options);
  EXPECT_EQ(again.status.ptp_domain, 7);
  EXPECT_LE(requests.load() - before, 12);
}

// The mapping on its own (no I/O), for the states the rig cannot reach without touching the clock.
sim::timing::Ptp4lAnswer answer_with_port(sim::timing::ptp::PortState state) {
  sim::timing::Ptp4lAnswer answer;
  answer.socket = "/test";
  sim::timing::ptp::PortDataSet port;
  port.port_number = 1;
  port.state = state;
  answer.ports.push_back(port);
  sim::timing::ptp::ParentDataSet parent;
  parent.grandmaster = {0x00, 0xa0, 0x69, 0xff, 0xfe, 0x0b, 0x55, 0x2d};
  answer.parent_ds = parent;
  answer.current_ds = sim::timing::ptp::CurrentDataSet{1, 3'000, 1'500};
  return answer;
}

TEST(HostClock, PortStatesMapToClockStatesAsDocumented) {
  using sim::timing::ptp::PortState;
  const sim::timing::KernelClock kernel{true, false, 1000, 0};
  const auto slave = sim::timing::host_clock_from(answer_with_port(PortState::slave), {}, kernel, 1);
  EXPECT_EQ(slave.status.state, ClockState::locked);
  EXPECT_EQ(slave.status.verdict, ClockVerdict::ok);
  EXPECT_EQ(slave.status.grandmaster, "00a069.fffe.0b552d");
  EXPECT_EQ(slave.description, "ptp slave of 00a069.fffe.0b552d, offset +3 µs");
  const auto master = sim::timing::host_clock_from(answer_with_port(PortState::master), {}, kernel, 1);
  EXPECT_EQ(master.status.state, ClockState::locked);
  EXPECT_NE(master.description.find("this host is the grandmaster"), std::string::npos);
  EXPECT_EQ(sim::timing::host_clock_from(answer_with_port(PortState::faulty), {}, kernel, 1).status.state,
            ClockState::holdover);
  EXPECT_EQ(sim::timing::host_clock_from(answer_with_port(PortState::listening), {}, kernel, 1).status.state,
            ClockState::acquiring);
  auto gptp = answer_with_port(PortState::slave);
  gptp.transport_specific = 1;
  EXPECT_EQ(sim::timing::host_clock_from(gptp, {}, kernel, 1).status.source, ClockSource::gptp);
  // A boundary clock: its slave port says how the host is synchronised, not its master ports.
  auto boundary = answer_with_port(PortState::master);
  boundary.ports.push_back({{}, 2, PortState::slave});
  EXPECT_EQ(sim::timing::host_clock_from(boundary, {}, kernel, 1).description.rfind("ptp slave of", 0), 0u);
}

}  // namespace
