// SPDX-License-Identifier: Apache-2.0
// What one kind of work in sim_foxglove must not cost the others (review L4, L5): many
// subscribed channels share one waiting thread instead of a thread each, and a page picture
// being made holds up neither a Foxglove client nor another connection. The server runs in this
// process (the library), fed by real SIM writers, and is read by the tests' raw client. No
// timing is asserted: the render worker is held by a test hook until the test lets it go.
#include <gtest/gtest.h>
#include <poll.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "page_frames.hpp"
#include "raw_client.hpp"
#include "render_worker.hpp"
#include "sim/foxglove/server.hpp"
#include "sim/sim.hpp"

namespace {

using namespace sim_test_foxglove;

// --- The render worker held by the test (sim::foxglove::testing::before_picture). ----------------
struct RenderGate {
  std::mutex mutex;
  std::condition_variable changed;
  bool hold = false;
  int entered = 0;  // pictures started while held
};
RenderGate gate;

}  // namespace

// Defined here, so the library calls it before each picture (it is a weak symbol there).
void sim::foxglove::testing::before_picture() {
  std::unique_lock lock(gate.mutex);
  if (!gate.hold) return;
  ++gate.entered;
  gate.changed.notify_all();
  gate.changed.wait(lock, [] { return !gate.hold; });
}

namespace {

void hold_pictures() {
  std::lock_guard lock(gate.mutex);
  gate.hold = true;
  gate.entered = 0;
}

void release_pictures() {
  {
    std::lock_guard lock(gate.mutex);
    gate.hold = false;
  }
  gate.changed.notify_all();
}

// True once a picture is being made (and held); false if none started within the patience.
bool a_picture_is_held() {
  std::unique_lock lock(gate.mutex);
  return gate.changed.wait_for(lock, kPatience, [] { return gate.entered > 0; });
}

// A GET of the newest picture of `stream` (a name with its leading slash), built in place.
std::string picture_request(const std::string& stream) {
  std::string text = "GET /api/image?stream=%2F";
  text += stream.substr(1);
  text += " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  return text;
}

std::size_t threads_of_this_process() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& task : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

// Small mono8 camera streams, all written by one thread until the fixture ends.
class FoxgloveIsolation : public ::testing::Test {
 protected:
  void TearDown() override {
    release_pictures();  // a held picture would keep the server from stopping
    server_.reset();
    stop_.store(true);
    if (writer_thread_.joinable()) writer_thread_.join();
    for (const auto& s : streams_) (void)sim::destroy(s, true);
  }

  // Creates `count` streams of `width`×`height` mono8 images and starts writing them.
  void write_streams(std::size_t count, std::uint32_t width, std::uint32_t height) {
    std::vector<sim::Writer> writers;
    for (std::size_t i = 0; i < count; ++i) {
      streams_.push_back(unique_stream("fox_iso"));
      auto writer = sim::Writer::create(
          {.name = streams_.back(),
           .layout = sim::Layout::of(sim::ImageLayout::packed(width, height, sim::PixelFormat::mono8))});
      ASSERT_TRUE(writer) << writer.error().message;
      writers.push_back(std::move(writer.value()));
    }
    writer_thread_ = std::thread([this, writers = std::move(writers), size = width * height]() mutable {
      std::vector<std::byte> frame(size, std::byte{0x40});
      while (!stop_.load()) {
        for (auto& w : writers) (void)w.write(frame, sim::realtime_ns());
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  }

  void start_server(unsigned io_threads = 2) {
    sim::foxglove::ServerOptions options;
    options.io_threads = io_threads;
    options.port = 0;
    options.streams = streams_;
    options.poll_interval = std::chrono::milliseconds(100);
    auto server = sim::foxglove::Server::start(options);
    ASSERT_TRUE(server) << server.error().message;
    server_.emplace(std::move(server.value()));
  }

  std::uint16_t port() const { return server_->port(); }

  // Connects the client and reads advertisements until every stream's image channel is known;
  // returns their channel ids (empty if the server never advertised them all).
  std::vector<std::uint32_t> open_client(RawClient& client) {
    const auto head = client.handshake();
    if (!head || head->find(" 101 ") == std::string::npos) return {};
    std::set<std::string> missing;
    for (const auto& s : streams_) missing.insert(s + "/image_raw");
    std::vector<std::uint32_t> channels;
    while (!missing.empty()) {
      const auto advertise = client.read_text_with("\"advertise\"");
      if (!advertise) return {};
      const auto parsed = nlohmann::json::parse(*advertise);
      for (const auto& c : parsed.at("channels")) {
        if (missing.erase(c.at("topic").get<std::string>()) > 0) {
          channels.push_back(c.at("id").get<std::uint32_t>());
        }
      }
    }
    return channels;
  }

  std::vector<std::string> streams_;
  std::optional<sim::foxglove::Server> server_;
  std::thread writer_thread_;
  std::atomic<bool> stop_{false};
};

// Review L4: a pump thread per subscribed channel made 300 slow channels cost 300 threads.
// 130 channels (more than one WaitSet's 128 readers) must cost at most two threads, and every
// one of them must still deliver frames.
TEST_F(FoxgloveIsolation, ManySubscribedChannelsShareOneWaitingThreadAndEachDeliversFrames) {
  constexpr std::size_t kChannels = 130;
  write_streams(kChannels, 32, 24);
  start_server();
  RawClient client(port());
  const std::vector<std::uint32_t> channels = open_client(client);
  ASSERT_EQ(channels.size(), kChannels) << "not every stream was advertised";
  const std::size_t threads_before = threads_of_this_process();

  std::string request = R"({"op":"subscribe","subscriptions":[)";
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (i > 0) request += ',';
    request += R"({"id":)";
    request += std::to_string(i);
    request += R"(,"channelId":)";
    request += std::to_string(channels[i]);
    request += '}';
  }
  request += "]}";
  ASSERT_TRUE(client.send_text(request));
  std::set<std::uint32_t> silent;
  for (std::uint32_t i = 0; i < kChannels; ++i) silent.insert(i);
  while (!silent.empty()) {
    const auto frame = client.read_frame();
    ASSERT_TRUE(frame) << silent.size() << " subscriptions got no frame, e.g. " << *silent.begin();
    if (const auto message = message_data(*frame)) silent.erase(message->subscription_id);
  }
  const std::size_t threads_after = threads_of_this_process();
  EXPECT_LE(threads_after, threads_before + 2)
      << kChannels << " subscribed channels took " << threads_after - threads_before
      << " threads: one per channel, not one per 128";
}

// Review L5: pictures were made on the io threads that write the Foxglove clients' frames.
// With one io thread and the render worker held in the middle of a picture, a Foxglove client
// still subscribes and gets frames, and another connection gets the stream table.
TEST_F(FoxgloveIsolation, APictureBeingMadeHoldsUpNeitherFoxgloveClientsNorOtherConnections) {
  write_streams(1, 320, 240);
  start_server(/*io_threads=*/1);
  hold_pictures();
  RawClient page(port());
  ASSERT_TRUE(page.send_raw(picture_request(streams_[0])));
  ASSERT_TRUE(a_picture_is_held()) << "the page's picture was never started";

  RawClient viewer(port());
  const auto channels = open_client(viewer);
  ASSERT_EQ(channels.size(), 1u) << "the Foxglove client was not served while a picture was made";
  ASSERT_TRUE(viewer.send_text(subscribe_request(7, channels[0])));
  std::optional<MessageData> message;
  while (!message) {
    const auto frame = viewer.read_frame();
    ASSERT_TRUE(frame) << "no frame reached the Foxglove client while a picture was made";
    message = message_data(*frame);
  }
  EXPECT_EQ(message->subscription_id, 7u);
  RawClient other(port());
  const auto table = other.get("/api/streams");
  ASSERT_TRUE(table) << "another connection was not answered while a picture was made";
  EXPECT_NE(table->find(" 200 "), std::string::npos) << *table;

  release_pictures();
  const auto picture = page.read_head();
  ASSERT_TRUE(picture);
  EXPECT_NE(picture->find(" 200 "), std::string::npos) << *picture;
  EXPECT_NE(picture->find("image/jpeg"), std::string::npos) << *picture;
}

// The pictures waiting for the worker are bounded: with one being made (held) and the queue
// full, the next request is answered at once with 503 and Retry-After, not queued; once the
// worker is let go every queued request gets its picture.
TEST_F(FoxgloveIsolation, PictureRequestsBeyondTheQueueGetA503WithRetryAfter) {
  write_streams(1, 320, 240);
  start_server();
  hold_pictures();
  const std::string get = picture_request(streams_[0]);
  RawClient first(port());
  ASSERT_TRUE(first.send_raw(get));
  ASSERT_TRUE(a_picture_is_held());

  constexpr std::size_t kWaiting = sim::foxglove::RenderWorker::kQueueLimit + 1;
  std::vector<std::unique_ptr<RawClient>> pages;
  std::vector<pollfd> polls;
  for (std::size_t i = 0; i < kWaiting; ++i) {
    pages.push_back(std::make_unique<RawClient>(port()));
    ASSERT_TRUE(pages.back()->send_raw(get));
    polls.push_back({pages.back()->fd(), POLLIN, 0});
  }
  // Exactly one request does not fit; its answer is the only one while the worker is held.
  ASSERT_GT(::poll(polls.data(), polls.size(), 20'000), 0) << "no request was refused";
  const auto refused = std::find_if(polls.begin(), polls.end(), [](const pollfd& p) { return p.revents != 0; });
  const auto head = pages[static_cast<std::size_t>(refused - polls.begin())]->read_head();
  ASSERT_TRUE(head);
  EXPECT_NE(head->find(" 503 "), std::string::npos) << *head;
  EXPECT_NE(head->find("Retry-After: 1"), std::string::npos) << *head;

  release_pictures();
  for (std::size_t i = 0; i < kWaiting; ++i) {
    if (static_cast<std::ptrdiff_t>(i) == refused - polls.begin()) continue;
    const auto answer = pages[i]->read_head();
    ASSERT_TRUE(answer) << "queued request " << i << " was never answered";
    EXPECT_NE(answer->find(" 200 "), std::string::npos) << *answer;
  }
}

}  // namespace
