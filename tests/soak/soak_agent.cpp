// SPDX-License-Identifier: Apache-2.0
// sim_soak_agent: the soak's own processes (tests/soak/soak.py starts them).
//
//   writer   --stream NAME --hz H (--image WxH | --points N)   verifiable frames, XXH3 checksum
//   read     --mode block|borrow|adaptive NAME:PERIOD_MS…     one thread per stream
//   waitset  NAME:PERIOD_MS…                                    one WaitSet over every stream
//   make-pictures DIR --frames N --width W --height H          the pictures sim_replay_video plays
//
// Readers print one JSON line per second with their counters and one line per violation at once
// (so a reader the chaos loop kills has already told what it saw). SIGTERM/SIGINT end any mode
// with exit 0 after a last line. What is checked, and why it is fair on a loaded machine:
// soak_check.hpp and tests/soak/README.md.
#include <signal.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "sim/reader.hpp"
#include "sim/wait_set.hpp"
#include "sim/writer.hpp"
#include "soak_check.hpp"
#include "soak_frames.hpp"

namespace {

using namespace std::chrono_literals;
using soak::monotonic_ns;
using soak::RunDelay;
using soak::StreamCheck;
using soak::Wait;

std::atomic<bool> g_stop{false};

void install_stop() {
  struct sigaction action {};
  action.sa_handler = [](int) { g_stop = true; };
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
}

// Break-it-on-purpose (tests/soak/README.md, "Faults"): SIM_SOAK_FAULT is a comma list of
// `fault` or `fault=argument`, honoured only with SIM_SOAK_TEST_MODE=1 (soak.py --fault sets both;
// a normal soak never breaks anything). The argument of a reader's fault is a '+' list of streams.
std::string fault_argument(const char* fault, bool* present = nullptr) {
  if (present != nullptr) *present = false;
  const char* mode = std::getenv("SIM_SOAK_TEST_MODE");
  const char* text = std::getenv("SIM_SOAK_FAULT");
  if (mode == nullptr || std::strcmp(mode, "1") != 0 || text == nullptr) return {};
  const std::string all = std::string(",") + text + ",";
  const std::string key = std::string(",") + fault;
  for (std::size_t at = all.find(key); at != std::string::npos; at = all.find(key, at + 1)) {
    const std::size_t after = at + key.size();
    if (all[after] != ',' && all[after] != '=') continue;
    if (present != nullptr) *present = true;
    if (all[after] == ',') return {};
    return all.substr(after + 1, all.find(',', after) - after - 1);
  }
  return {};
}

// Whether `fault` is on for this stream (its argument lists the stream).
bool fault_on(const char* fault, const std::string& stream) {
  const std::string streams = fault_argument(fault);
  for (std::size_t at = 0; at <= streams.size();) {
    const std::size_t end = std::min(streams.find('+', at), streams.size());
    if (streams.compare(at, end - at, stream) == 0 && end > at) return true;
    at = end + 1;
  }
  return false;
}

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "sim_soak_agent: %s.\nusage: sim_soak_agent writer --stream NAME --hz H "
               "(--image WxH | --points N) [--tear-every N]\n       sim_soak_agent read --mode "
               "block|borrow|adaptive NAME:PERIOD_MS...\n       sim_soak_agent waitset "
               "NAME:PERIOD_MS...\n       sim_soak_agent make-pictures DIR --frames N --width W "
               "--height H\n",
               why);
  std::exit(2);
}

// ---- the writer ---------------------------------------------------------------------------------

struct WriterOptions {
  std::string stream;
  double hz = 30;
  std::uint32_t width = 0, height = 0;  // an image stream (bgr8)
  std::uint64_t points = 0;             // or a point stream of up to this many points
  std::uint64_t tear_every = 0;         // the checks' own test: every Nth frame is torn on purpose
};

sim::Layout layout_of(const WriterOptions& o) {
  if (o.points > 0) return sim::Layout::of(sim::PointLayout::of(sim::PointType::lidar_point, o.points));
  return sim::Layout::of(sim::ImageLayout::packed(o.width, o.height, sim::PixelFormat::bgr8));
}

// Bytes of frame `seq`: fixed for images, varying for points (so a torn length would show).
std::size_t frame_bytes(const WriterOptions& o, std::uint64_t capacity, std::uint64_t seq) {
  if (o.points == 0) return capacity;
  const std::uint64_t n = o.points / 2 + soak::mix(seq) % (o.points / 2);
  return n * 24;
}

// The writer's own account of what it published: a line for every publish gap (two commits more
// than 1.5 periods apart: the writer itself paused, so every reader of the stream sees nothing
// new meanwhile) and a stats line a second. The soak tells a writer's (or the machine's) stall
// from a reader's lost wake-up by them.
class PublishLog {
 public:
  PublishLog(std::string stream, std::int64_t period_ns) : stream_(std::move(stream)), period_ns_(period_ns) {}
  void published(std::uint64_t seq, std::int64_t at_ns) {
    ++published_;
    if (last_ns_ != 0) {
      const std::int64_t gap = at_ns - last_ns_;
      max_interval_ns_ = std::max(max_interval_ns_, gap);
      if (2 * gap > 3 * period_ns_) {
        std::printf("{\"kind\":\"publish_gap\",\"stream\":\"%s\",\"seq\":%" PRIu64 ",\"from_ns\":%" PRId64
                    ",\"to_ns\":%" PRId64 ",\"gap_ms\":%.3f}\n",
                    stream_.c_str(), seq, last_ns_, at_ns, static_cast<double>(gap) / 1e6);
        std::fflush(stdout);
      }
    }
    last_ns_ = at_ns;
    if (at_ns - printed_ns_ > 1'000'000'000) print_stats(at_ns);
  }
  // A commit that took more than half a period: the frame became readable inside it, but its
  // wake-up came only as it returned, so every sleeping reader waited for the writer meanwhile.
  void committed(std::uint64_t seq, std::int64_t began_ns, std::int64_t returned_ns) {
    if (2 * (returned_ns - began_ns) <= period_ns_) return;
    std::printf("{\"kind\":\"publish_gap\",\"in_commit\":true,\"stream\":\"%s\",\"seq\":%" PRIu64
                ",\"from_ns\":%" PRId64 ",\"to_ns\":%" PRId64 ",\"gap_ms\":%.3f}\n",
                stream_.c_str(), seq, began_ns, returned_ns, static_cast<double>(returned_ns - began_ns) / 1e6);
    std::fflush(stdout);
  }

 private:
  void print_stats(std::int64_t at_ns) {
    printed_ns_ = at_ns;
    std::printf("{\"kind\":\"stats\",\"role\":\"writer\",\"stream\":\"%s\",\"published\":%" PRIu64
                ",\"max_publish_interval_ms\":%.3f}\n",
                stream_.c_str(), published_, static_cast<double>(max_interval_ns_) / 1e6);
    std::fflush(stdout);
  }

  std::string stream_;
  std::int64_t period_ns_;
  std::uint64_t published_ = 0;
  std::int64_t last_ns_ = 0, printed_ns_ = 0, max_interval_ns_ = 0;
};

int run_writer(const WriterOptions& o) {
  auto writer = sim::Writer::create({.name = o.stream, .layout = layout_of(o), .checksum = true});
  if (!writer) {
    std::fprintf(stderr, "sim_soak_agent: %s\n", writer.error().message.c_str());
    return 1;
  }
  std::vector<std::uint64_t> index_words(writer->capacity() / 8);
  for (std::size_t i = 0; i < index_words.size(); ++i) index_words[i] = soak::index_word(i);
  std::deque<std::int64_t> history;  // commit-return times, newest first
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / o.hz));
  // The fault "stale_region": a second region under the soak's names, left behind on exit.
  std::optional<sim::Writer> stale;
  if (fault_on("stale_region", o.stream)) {
    WriterOptions small;
    small.points = 16;
    auto w = sim::Writer::create({.name = o.stream + "_stale", .layout = layout_of(small)});
    if (w) stale.emplace(std::move(*w));
  }
  PublishLog log(o.stream, period.count());
  auto next = std::chrono::steady_clock::now();
  while (!g_stop) {
    const std::uint64_t seq = writer->last_seq() + 1;
    sim::Loan loan = writer->loan();
    const std::size_t size = frame_bytes(o, writer->capacity(), seq);
    const std::vector<std::int64_t> carried(history.begin(), history.end());
    soak::fill(loan.bytes().subspan(0, size), seq, carried, index_words);
    if (o.tear_every > 0 && seq % o.tear_every == 0) {  // its second half from the frame before
      soak::fill(loan.bytes().subspan(size / 2 / 8 * 8, size - size / 2 / 8 * 8), seq - 1, {}, index_words);
    }
    next += period;
    std::this_thread::sleep_until(next);
    const auto stamp = std::chrono::system_clock::now().time_since_epoch();
    const std::int64_t commit_began = monotonic_ns();
    if (std::move(loan).commit(size, std::chrono::duration_cast<std::chrono::nanoseconds>(stamp).count()) !=
        sim::WriteStatus::ok) {
      std::fprintf(stderr, "sim_soak_agent: the commit of frame %" PRIu64 " failed\n", seq);
      return 1;
    }
    // Taken after commit returned (wake-ups included): never earlier than a reader could see it.
    history.push_front(monotonic_ns());
    if (history.size() > soak::kHistory) history.pop_back();
    log.committed(seq, commit_began, history.front());
    log.published(seq, history.front());
    if (std::chrono::steady_clock::now() > next + 10 * period) next = std::chrono::steady_clock::now();
  }
  return 0;
}

// ---- what every reader does with a frame -------------------------------------------------------

struct StreamArg {
  std::string name;
  std::int64_t period_ns = 0;
};

StreamArg parse_stream(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) usage("a stream is NAME:PERIOD_MS");
  return {text.substr(0, colon), static_cast<std::int64_t>(std::stod(text.substr(colon + 1)) * 1e6)};
}

// Whole: a point frame of the pcap replay passes its structure check, anything else its pattern.
bool whole(sim::span<const std::byte> bytes, const sim::FrameInfo& info) {
  const std::span<const std::byte> frame(bytes.data(), bytes.size());
  const bool ours = frame.size() >= 8 && soak::word_at(frame, 0) == soak::kMagic;
  if (!ours && info.layout.kind == sim::LayoutKind::points) return soak::verify_points(frame);
  return soak::verify(frame) == soak::Verdict::whole;
}

std::int64_t carried(sim::span<const std::byte> bytes, const sim::FrameInfo& info, std::uint64_t last_seq) {
  if (last_seq == 0 || info.seq <= last_seq + 1) return 0;
  return soak::carried_publish(std::span<const std::byte>(bytes.data(), bytes.size()),
                               info.seq - last_seq - 1);
}

// The writer's main thread's run delay, following the writer as it is restarted.
class WriterDelay {
 public:
  std::int64_t now(sim::Reader& reader) {
    const std::int64_t t = monotonic_ns();
    if (t - refreshed_ns_ > 200'000'000) {  // a restarted writer is a new process
      refreshed_ns_ = t;
      const int pid = reader.status().writer_pid;
      if (pid != pid_) {
        pid_ = pid;
        delay_ = pid > 0 ? RunDelay::of_process(pid) : RunDelay();
      }
    }
    return delay_.now();
  }
  int pid() const { return pid_; }

 private:
  int pid_ = 0;
  RunDelay delay_;
  std::int64_t refreshed_ns_ = 0;
};

// Measures one wait: when it began, whether a newer frame was already there, and the run delays.
class WaitClock {
 public:
  void begin(sim::Reader& reader, const StreamCheck& check, WriterDelay& writer) {
    wait_ = {};
    wait_.start_ns = monotonic_ns();
    own_start_ = own_.now();
    writer_start_ = writer.now(reader);
    steal_start_ = soak::Steal::now();
    pid_ = writer.pid();
    const auto age = reader.newest_age().count();
    wait_.newer_at_start = age >= 0 && check.last_seq() != 0 &&
                           wait_.start_ns - age > check.last_publish_ns() + 100'000;
  }
  const Wait& end(sim::Reader& reader, WriterDelay& writer) {
    wait_.end_ns = monotonic_ns();
    const std::int64_t own_end = own_.now();
    const std::int64_t writer_end = writer.now(reader);
    wait_.own_delay_ns = own_start_ >= 0 && own_end >= 0 ? own_end - own_start_ : 0;
    wait_.steal_ns = soak::Steal::now() - steal_start_;
    wait_.writer_delay_known = writer.pid() == pid_ && writer_start_ >= 0 && writer_end >= 0;
    wait_.writer_delay_ns = wait_.writer_delay_known ? writer_end - writer_start_ : 0;
    return wait_;
  }
  // After a timeout: how long a frame newer than the last delivered had been waiting, net.
  std::int64_t unserved_ns(sim::Reader& reader, const StreamCheck& check) const {
    const auto age = reader.newest_age().count();
    if (age < 0 || check.last_seq() == 0) return 0;
    const std::int64_t newest_publish = wait_.end_ns - age;
    if (newest_publish <= check.last_publish_ns() + 100'000) return 0;
    return wait_.end_ns - std::max(wait_.start_ns, newest_publish) - wait_.own_delay_ns -
           wait_.writer_delay_ns - wait_.steal_ns;
  }

 private:
  RunDelay own_ = RunDelay::this_thread();
  Wait wait_;
  std::int64_t own_start_ = -1, writer_start_ = -1, steal_start_ = 0;
  int pid_ = 0;
};

std::optional<sim::Reader> open_when_there(const std::string& name, sim::WaitMode mode) {
  while (!g_stop) {
    if (auto reader = sim::Reader::open(name, {.wait_mode = mode})) return std::move(*reader);
    std::this_thread::sleep_for(20ms);
  }
  return std::nullopt;
}

// Reads the newest frame (copy or borrow) and checks it. False when nothing was delivered.
// `reopens_before`: the reader's count of regions followed when the wait began.
bool take_frame(sim::Reader& reader, StreamCheck& check, bool borrow, std::vector<std::byte>& buffer,
                Wait wait, std::uint64_t reopens_before) {
  if (borrow) {
    sim::Borrow b = reader.borrow();
    if (b.status() == sim::ReadStatus::checksum_mismatch) check.torn_checksum(b.info().seq);
    if (b.status() != sim::ReadStatus::new_frame) return false;
    const bool ok = whole(b.bytes(), b.info());
    const std::int64_t carried_ns = carried(b.bytes(), b.info(), check.last_seq());
    wait.new_region = reader.stats().reopens != reopens_before;
    if (!b.still_valid()) {
      check.overwritten();
      return false;
    }
    check.delivered(b.info(), ok, wait, carried_ns);
    return true;
  }
  sim::FrameInfo info;
  if (buffer.size() < reader.capacity()) buffer.resize(reader.capacity());
  const auto status = reader.read(buffer, info);
  if (status == sim::ReadStatus::checksum_mismatch) check.torn_checksum(info.seq);
  if (status != sim::ReadStatus::new_frame) return false;
  const sim::span<const std::byte> bytes(buffer.data(), info.size);
  wait.new_region = reader.stats().reopens != reopens_before;
  check.delivered(info, whole(bytes, info), wait, carried(bytes, info, check.last_seq()));
  return true;
}

// ---- readers of one stream: blocking, borrowing, adaptive ---------------------------------------

// The checks' own test: SIM_SOAK_OVERSLEEP_MS makes every wait sleep that long first, as a reader
// that slept through a frame would (a plain sleep, not a run delay, so it must be reported).
std::chrono::milliseconds oversleep() {
  const char* text = std::getenv("SIM_SOAK_OVERSLEEP_MS");
  return std::chrono::milliseconds(text ? std::atoi(text) : 0);
}

// The faults of a reader, as a transport that loses wake-ups would look to it (soak.py --fault):
// "lost_wakeups": never woken, it finds frames only when it looks again once per 100 ms region
// check slice; "half_frames": after every third wake-up it sleeps through the next three frames,
// so it gets half of them. Three at a time, not every other one: the soak excuses skipped frames
// that the run delays and steal of the wait cover, and on a loaded machine (CI) those covered a
// single frame's period in about half the waits, so a reader that lost every other wake-up passed
// the floor; three periods at once are rarely covered.
struct ReaderFaults {
  bool never_woken = false;
  bool half_frames = false;
};
inline constexpr std::uint64_t kFramesSleptThrough = 3;

sim::ReadStatus faulty_wait(sim::Reader& reader, const ReaderFaults& faults, std::uint64_t& woken,
                            std::int64_t period_ns) {
  if (faults.never_woken) {
    // The slice begins when the wait does, at any moment of the writer's period.
    thread_local std::uint64_t state = static_cast<std::uint64_t>(monotonic_ns());
    state = soak::mix(state);
    std::this_thread::sleep_for(std::chrono::nanoseconds(static_cast<std::int64_t>(state % soak::kRegionCheckSliceNs)));
    return reader.wait(0ms);
  }
  const auto status = reader.wait(1s);
  if (faults.half_frames && status == sim::ReadStatus::new_frame && ++woken % kFramesSleptThrough == 0) {
    const auto periods = static_cast<std::int64_t>(kFramesSleptThrough);
    std::this_thread::sleep_for(std::chrono::nanoseconds(periods * period_ns + period_ns / 4));
  }
  return status;
}

void read_stream(StreamCheck& check, sim::WaitMode mode, bool borrow) {
  static const auto inject = oversleep();
  const ReaderFaults faults{fault_on("lost_wakeups", check.name()), fault_on("half_frames", check.name())};
  std::uint64_t woken = 0;
  std::vector<std::byte> buffer;
  WaitClock clock;
  while (!g_stop) {
    auto reader = open_when_there(check.name(), mode);
    if (!reader) return;
    check.restart();
    WriterDelay writer;
    std::uint64_t reopens = reader->stats().reopens;
    std::int64_t gone_since = 0;
    while (!g_stop) {
      const std::uint64_t reopens_before = reader->stats().reopens;
      clock.begin(*reader, check, writer);
      if (inject.count() > 0) std::this_thread::sleep_for(inject);
      const auto status = faulty_wait(*reader, faults, woken, check.period_ns());
      const Wait& wait = clock.end(*reader, writer);
      if (status == sim::ReadStatus::new_frame) {
        take_frame(*reader, check, borrow, buffer, wait, reopens_before);
        gone_since = 0;
      } else if (status == sim::ReadStatus::no_new_frame) {
        check.timed_out_with_newer(clock.unserved_ns(*reader, check), reader->stats().reopens != reopens_before);
      }
      if (reader->stats().reopens != reopens) {  // replaced under the same name: followed
        reopens = reader->stats().reopens;
        check.replaced();
      }
      if (status == sim::ReadStatus::new_frame || status == sim::ReadStatus::no_new_frame) continue;
      // Writer gone (killed by the chaos loop), stale, or the region removed: look again by name
      // after a while (a new writer may have created a new region).
      if (gone_since == 0) gone_since = monotonic_ns();
      if (status == sim::ReadStatus::region_invalid || monotonic_ns() - gone_since > 2'000'000'000) break;
      std::this_thread::sleep_for(50ms);
    }
  }
}

// ---- one WaitSet over every stream -------------------------------------------------------------

struct SetMember {
  StreamCheck* check;
  std::unique_ptr<sim::Reader> reader;
  WriterDelay writer;
  WaitClock clock;
  std::uint64_t reopens = 0;
  std::int64_t gone_since = 0;
};

// Opens what exists now; the set is rebuilt when a stream is missing or stays gone.
std::vector<std::unique_ptr<SetMember>> open_members(std::deque<StreamCheck>& checks) {
  std::vector<std::unique_ptr<SetMember>> members;
  for (auto& check : checks) {
    auto reader = sim::Reader::open(check.name());
    if (!reader) continue;
    auto m = std::make_unique<SetMember>();
    m->check = &check;
    m->reader = std::make_unique<sim::Reader>(std::move(*reader));
    m->reopens = m->reader->stats().reopens;
    check.restart();
    members.push_back(std::move(m));
  }
  return members;
}

// One wait of the set and the frames it made ready. False: rebuild the set.
bool wait_once(sim::WaitSet& set, std::vector<std::unique_ptr<SetMember>>& members, std::vector<std::byte>& buffer) {
  for (auto& m : members) m->clock.begin(*m->reader, *m->check, m->writer);
  const auto ready = set.wait(1s);
  bool healthy = true;
  for (std::size_t i = 0; i < members.size(); ++i) {
    auto& m = *members[i];
    const Wait& wait = m.clock.end(*m.reader, m.writer);
    if ((ready && *ready == i) || set.ready(i)) {
      if (take_frame(*m.reader, *m.check, true, buffer, wait, m.reopens)) m.gone_since = 0;
    } else if (!ready) {
      m.check->timed_out_with_newer(m.clock.unserved_ns(*m.reader, *m.check), m.reader->stats().reopens != m.reopens);
    }
    if (m.reader->stats().reopens != m.reopens) {
      m.reopens = m.reader->stats().reopens;
      m.check->replaced();
    }
    if (m.reader->writer_alive()) {
      m.gone_since = 0;
    } else if (m.gone_since == 0) {
      m.gone_since = monotonic_ns();
    } else if (monotonic_ns() - m.gone_since > 2'000'000'000) {
      healthy = false;
    }
  }
  return healthy;
}

void read_wait_set(std::deque<StreamCheck>& checks) {
  std::vector<std::byte> buffer;
  while (!g_stop) {
    auto members = open_members(checks);
    sim::WaitSet set;
    for (auto& m : members) {
      if (!set.add(*m->reader)) usage("a WaitSet refused a reader");
    }
    const std::int64_t built = monotonic_ns();
    while (!g_stop && wait_once(set, members, buffer)) {
      // A stream that did not exist when the set was built: rebuild after a while to include it.
      if (members.size() < checks.size() && monotonic_ns() - built > 2'000'000'000) break;
    }
    if (members.empty()) std::this_thread::sleep_for(100ms);
  }
}

// ---- reporting ----------------------------------------------------------------------------------

void print_stats(const char* role, std::deque<StreamCheck>& checks, bool final) {
  std::string line = std::string("{\"kind\":\"stats\",\"role\":\"") + role + "\",\"final\":" +
                     (final ? "true" : "false") + ",\"streams\":{";
  bool first = true;
  for (auto& check : checks) {
    const auto c = check.snapshot();
    char text[512];
    std::snprintf(text, sizeof text,
                  "%s\"%s\":{\"frames\":%" PRIu64 ",\"torn\":%" PRIu64 ",\"out_of_order\":%" PRIu64
                  ",\"missed\":%" PRIu64 ",\"timed\":%" PRIu64 ",\"untimed\":%" PRIu64
                  ",\"skipped\":%" PRIu64 ",\"lost\":%" PRIu64 ",\"overwritten\":%" PRIu64 ",\"opens\":%" PRIu64 ",\"replaced\":%" PRIu64
                  ",\"worst_stall_ms\":%.3f}",
                  first ? "" : ",", check.name().c_str(), c.frames, c.torn, c.out_of_order, c.missed,
                  c.timed, c.untimed, c.skipped, c.lost, c.overwritten, c.reopens, c.replacements, static_cast<double>(c.worst_stall_ns) / 1e6);
    line += text;
    first = false;
  }
  line += "}}";
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

int run_readers(const std::string& mode, const std::vector<std::string>& streams) {
  std::deque<StreamCheck> checks;  // stable addresses for the threads
  for (const auto& s : streams) {
    const auto arg = parse_stream(s);
    checks.emplace_back(arg.name, arg.period_ns);
  }
  std::vector<std::thread> threads;
  bool leak = false;
  const std::string leak_kib = fault_argument("leak", &leak);
  if (leak && mode == "block") {  // the fault "leak": a small steady leak, touched (so resident)
    const long kib = leak_kib.empty() ? 64 : std::atol(leak_kib.c_str());
    std::thread([kib] {
      while (!g_stop) {
        auto* lost = static_cast<char*>(std::malloc(static_cast<std::size_t>(kib) * 1024));
        if (lost != nullptr) std::memset(lost, 0x5A, static_cast<std::size_t>(kib) * 1024);
        std::this_thread::sleep_for(1s);
      }
    }).detach();
  }
  if (mode == "waitset") {
    threads.emplace_back([&] { read_wait_set(checks); });
  } else {
    const auto wait_mode = mode == "adaptive" ? sim::WaitMode::adaptive : sim::WaitMode::block;
    const bool borrow = mode == "borrow";
    if (mode != "block" && mode != "adaptive" && !borrow) usage("--mode is block, borrow or adaptive");
    for (auto& check : checks) threads.emplace_back([&check, wait_mode, borrow] { read_stream(check, wait_mode, borrow); });
  }
  while (!g_stop) {
    for (int i = 0; i < 10 && !g_stop; ++i) std::this_thread::sleep_for(100ms);
    print_stats(mode.c_str(), checks, false);
  }
  for (auto& t : threads) t.join();
  print_stats(mode.c_str(), checks, true);
  return 0;
}

// ---- the pictures sim_replay_video plays ----------------------------------------------------------

int make_pictures(const std::string& path, int frames, int width, int height) {
  std::vector<cv::Mat> pictures;
  for (int k = 0; k < frames; ++k) {
    const std::uint64_t tag = soak::kVideoTag | static_cast<std::uint64_t>(k);
    cv::Mat picture(height, width, CV_8UC3);
    auto* words = reinterpret_cast<std::uint64_t*>(picture.data);
    for (std::size_t i = 0; i < picture.total() * 3 / 8; ++i) words[i] = soak::pattern_word(tag, i);
    words[0] = soak::kMagic;
    words[1] = tag;
    for (std::size_t i = 2; i < soak::kHeaderWords; ++i) words[i] = 0;
    pictures.push_back(picture);
  }
  // BMP: read back exactly, and the cheapest picture to decode (seven 1920x1200 streams at 30 Hz
  // from a video codec cost more CPU than a 2-core machine has).
  for (int k = 0; k < frames; ++k) {
    char file[32];
    std::snprintf(file, sizeof file, "/%03d.bmp", k);
    if (!cv::imwrite(path + file, pictures[k])) {
      std::fprintf(stderr, "sim_soak_agent: cannot write %s%s\n", path.c_str(), file);
      return 1;
    }
    const cv::Mat back = cv::imread(path + file, cv::IMREAD_COLOR);
    if (back.total() != pictures[k].total() || back.type() != CV_8UC3 || !back.isContinuous() ||
        std::memcmp(back.data, pictures[k].data, back.total() * 3) != 0) {
      std::fprintf(stderr, "sim_soak_agent: %s%s does not read back exactly\n", path.c_str(), file);
      return 1;
    }
  }
  return 0;
}

std::string value_after(std::vector<std::string>& args, const std::string& key) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == key) {
      std::string v = args[i + 1];
      args.erase(args.begin() + static_cast<std::ptrdiff_t>(i), args.begin() + static_cast<std::ptrdiff_t>(i) + 2);
      return v;
    }
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) usage("which mode?");
  const std::string mode = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  install_stop();
  if (mode == "writer") {
    WriterOptions o;
    o.stream = value_after(args, "--stream");
    const std::string hz = value_after(args, "--hz");
    const std::string image = value_after(args, "--image");
    const std::string points = value_after(args, "--points");
    if (o.stream.empty() || hz.empty() || image.empty() == points.empty()) usage("writer needs --stream, --hz and --image or --points");
    o.hz = std::stod(hz);
    const std::string tear = value_after(args, "--tear-every");
    if (!tear.empty()) o.tear_every = std::stoull(tear);
    if (!points.empty()) o.points = std::stoull(points);
    if (!image.empty() && std::sscanf(image.c_str(), "%ux%u", &o.width, &o.height) != 2) usage("--image is WxH");
    return run_writer(o);
  }
  if (mode == "read") {
    const std::string how = value_after(args, "--mode");
    if (args.empty()) usage("read needs streams");
    return run_readers(how, args);
  }
  if (mode == "waitset") {
    if (args.empty()) usage("waitset needs streams");
    return run_readers("waitset", args);
  }
  if (mode == "make-pictures") {
    const std::string frames = value_after(args, "--frames");
    const std::string width = value_after(args, "--width");
    const std::string height = value_after(args, "--height");
    if (args.size() != 1 || frames.empty() || width.empty() || height.empty()) usage("make-pictures DIR --frames N --width W --height H");
    return make_pictures(args[0], std::stoi(frames), std::stoi(width), std::stoi(height));
  }
  usage("unknown mode");
}
