// SPDX-License-Identifier: Apache-2.0
// sim/opencv.hpp over real regions: a driver decodes into a cv::Mat over its loan, a reader
// views the borrowed slot as a cv::Mat without a copy, or copies it out; a copy made while the
// writer overwrites the slot is reported, never handed over torn.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <opencv2/core.hpp>
#include <thread>

#include "sim/imaging/image_format.hpp"
#include "sim/opencv.hpp"
#include "sim/sim.hpp"

namespace sim {
namespace {

using namespace std::chrono_literals;

std::string unique_stream() {
  static int counter = 0;
  return "/test_camera_cv_" + std::to_string(getpid()) + "_" + std::to_string(counter++);
}

struct Stream {
  explicit Stream(const ImageLayout& layout) : name(unique_stream()) {
    StreamSpec spec;
    spec.name = name;
    spec.layout = Layout::of(layout);
    auto created = Writer::create(spec);
    EXPECT_TRUE(created) << created.error().message;
    writer.emplace(std::move(created.value()));
    auto opened = Reader::open(name);
    EXPECT_TRUE(opened) << opened.error().message;
    reader.emplace(std::move(opened.value()));
  }
  ~Stream() {
    reader.reset();
    writer.reset();
    (void)destroy(name, true);
  }
  std::string name;
  std::optional<Writer> writer;
  std::optional<Reader> reader;
};

TEST(OpenCv, LoanMatIsTheSlotAndBorrowMatIsTheFrame) {
  const ImageLayout layout = imaging::make_layout(64, 48, PixelFormat::bgr8);
  Stream stream(layout);
  Loan loan = stream.writer->loan();
  cv::Mat slot = as_mat(loan, layout);
  ASSERT_FALSE(slot.empty());
  EXPECT_EQ(static_cast<void*>(slot.data), static_cast<void*>(loan.bytes().data()));
  EXPECT_EQ(slot.type(), CV_8UC3);
  slot.setTo(cv::Scalar(10, 20, 30));
  slot.at<cv::Vec3b>(47, 63) = {1, 2, 3};
  ASSERT_EQ(std::move(loan).commit(layout.frame_bytes(), 42), WriteStatus::ok);

  Borrow borrow = stream.reader->borrow();
  ASSERT_EQ(borrow.status(), ReadStatus::new_frame);
  const cv::Mat view = as_mat(borrow);
  ASSERT_EQ(view.rows, 48);
  ASSERT_EQ(view.cols, 64);
  EXPECT_EQ(static_cast<const void*>(view.data), static_cast<const void*>(borrow.bytes().data()));
  EXPECT_EQ(view.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
  EXPECT_EQ(view.at<cv::Vec3b>(47, 63), cv::Vec3b(1, 2, 3));
  cv::Mat kept;
  EXPECT_TRUE(copy_to(borrow, kept));
  EXPECT_TRUE(borrow.still_valid());
  EXPECT_NE(kept.data, view.data);
  EXPECT_EQ(cv::norm(kept, view, cv::NORM_INF), 0.0);
}

TEST(OpenCv, ReadMatKeepsAPaddedStrideAndReusesItsBuffer) {
  const ImageLayout layout = imaging::make_layout(64, 48, PixelFormat::yuyv, 160);
  Stream stream(layout);
  Loan loan = stream.writer->loan();
  cv::Mat slot = as_mat(loan, layout);
  ASSERT_EQ(slot.step[0], 160u);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) slot.at<cv::Vec2b>(y, x) = {static_cast<uchar>(x), static_cast<uchar>(y)};
  }
  ASSERT_EQ(std::move(loan).commit(layout.frame_bytes(), 1), WriteStatus::ok);

  cv::Mat out;
  FrameInfo info;
  ASSERT_EQ(read_mat(*stream.reader, out, info), ReadStatus::new_frame);
  ASSERT_EQ(out.cols, 64);
  ASSERT_EQ(out.rows, 48);
  EXPECT_EQ(out.type(), CV_8UC2);
  EXPECT_EQ(out.at<cv::Vec2b>(47, 63), cv::Vec2b(63, 47));
  EXPECT_EQ(out.at<cv::Vec2b>(5, 9), cv::Vec2b(9, 5));

  const uchar* first = out.data;
  Loan again = stream.writer->loan();
  as_mat(again, layout).setTo(cv::Scalar(7, 8));
  ASSERT_EQ(std::move(again).commit(layout.frame_bytes(), 2), WriteStatus::ok);
  ASSERT_EQ(read_mat(*stream.reader, out, info), ReadStatus::new_frame);
  EXPECT_EQ(out.data, first);  // no allocation per frame
  EXPECT_EQ(out.at<cv::Vec2b>(47, 63), cv::Vec2b(7, 8));
}

TEST(OpenCv, NoMatrixForCompressedOrShortFrames) {
  const ImageLayout jpeg = imaging::make_layout(64, 48, PixelFormat::mjpeg);
  std::vector<std::byte> bytes(64 * 48 * 3);
  EXPECT_TRUE(as_mat(jpeg, std::span<std::byte>(bytes)).empty());
  EXPECT_EQ(cv_type(jpeg), -1);
  const ImageLayout bgr = imaging::make_layout(64, 48, PixelFormat::bgr8);
  EXPECT_FALSE(as_mat(bgr, std::span<std::byte>(bytes)).empty());
  EXPECT_TRUE(as_mat(bgr, std::span<std::byte>(bytes).first(bytes.size() - 1)).empty());
  EXPECT_EQ(cv_type(imaging::make_layout(4, 4, PixelFormat::mono16)), CV_16UC1);
}

// A reader copying frames while the writer rewrites the slots never keeps a torn copy: every
// copy that copy_to() vouches for is one uniform frame.
TEST(OpenCv, CopiesUnderConcurrentWritesAreWholeFrames) {
  const ImageLayout layout = imaging::make_layout(320, 240, PixelFormat::mono8);
  Stream stream(layout);
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    for (int k = 0; !stop.load(); ++k) {
      Loan loan = stream.writer->loan();
      as_mat(loan, layout).setTo(cv::Scalar(k % 256));
      (void)std::move(loan).commit(layout.frame_bytes(), k);
    }
  });
  int vouched = 0;
  cv::Mat copy;
  const auto deadline = std::chrono::steady_clock::now() + 500ms;
  while (std::chrono::steady_clock::now() < deadline) {
    Borrow borrow = stream.reader->borrow();
    if (borrow.status() != ReadStatus::new_frame) continue;
    if (!copy_to(borrow, copy)) continue;
    ++vouched;
    double low = 0;
    double high = 0;
    cv::minMaxLoc(copy, &low, &high);
    ASSERT_EQ(low, high) << "torn copy after " << vouched << " frames";
  }
  stop = true;
  writer.join();
  EXPECT_GT(vouched, 0);
}

}  // namespace
}  // namespace sim
