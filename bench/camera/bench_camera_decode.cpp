// SPDX-License-Identifier: Apache-2.0
// Camera decode cost, ours against OpenCV's, side by side at 640×480 and 1920×1200:
//   YUYV → BGR   sim::imaging::FrameDecoder into the loaned slot, then commit (the full "dequeued
//                buffer to visible to readers" path)  vs  cv::cvtColor into a fresh cv::Mat;
//   MJPEG → BGR  tjDecompress2 into the loaned slot, then commit  vs  cv::imdecode + copy into
//                the slot.
// Ratios (ours / OpenCV's time, lower is better) are printed after the table.
#include <benchmark/benchmark.h>
#include <turbojpeg.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "sim/imaging/decoder.hpp"
#include "sim/sim.hpp"

namespace {

using sim::imaging::FrameDecoder;
using sim::imaging::make_layout;

// A camera-like scene (gradients, discs, text, sensor noise) so JPEG sizes are realistic.
cv::Mat scene(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) = {static_cast<uchar>(x * 255 / width),
                                   static_cast<uchar>(y * 255 / height), 128};
    }
  }
  cv::RNG rng(7);
  for (int i = 0; i < 200; ++i) {
    cv::circle(image, {rng.uniform(0, width), rng.uniform(0, height)}, rng.uniform(5, width / 20),
               cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255)),
               cv::FILLED);
  }
  cv::putText(image, "SIM camera benchmark", {width / 10, height / 2}, cv::FONT_HERSHEY_SIMPLEX,
              width / 400.0, cv::Scalar(255, 255, 255), 3);
  cv::Mat noise(image.size(), CV_8UC3);
  cv::randn(noise, cv::Scalar::all(0), cv::Scalar::all(6));
  image += noise;
  return image;
}

std::vector<unsigned char> jpeg_422(const cv::Mat& bgr) {
  tjhandle encoder = tjInitCompress();
  unsigned char* out = nullptr;
  unsigned long size = 0;
  tjCompress2(encoder, bgr.data, bgr.cols, static_cast<int>(bgr.step[0]), bgr.rows, TJPF_BGR, &out,
              &size, TJSAMP_422, 85, 0);
  std::vector<unsigned char> bytes(out, out + size);
  tjFree(out);
  tjDestroy(encoder);
  return bytes;
}

// A real SIM stream whose loans are the destination, as in the drivers.
struct Stream {
  explicit Stream(const sim::ImageLayout& layout) {
    name = "/bench_camera_" + std::to_string(getpid()) + "_" + std::to_string(counter++);
    sim::StreamSpec spec;
    spec.name = name;
    spec.layout = sim::Layout::of(layout);
    auto created = sim::Writer::create(spec);
    if (created) writer.emplace(std::move(created.value()));
  }
  ~Stream() {
    writer.reset();
    (void)sim::destroy(name, true);
  }
  static inline int counter = 0;
  std::string name;
  std::optional<sim::Writer> writer;
};

std::span<const std::byte> bytes_of(const cv::Mat& m) {
  return {reinterpret_cast<const std::byte*>(m.data), m.total() * m.elemSize()};
}

void YuyvToBgr_Sim(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  cv::Mat yuyv(h, w, CV_8UC2);
  cv::randu(yuyv, 0, 255);
  auto decoder = FrameDecoder::create(make_layout(static_cast<std::uint32_t>(w),
                                                  static_cast<std::uint32_t>(h), sim::PixelFormat::yuyv),
                                      sim::imaging::OutputFormat::bgr8);
  Stream stream(decoder->output_layout());
  if (!stream.writer) return state.SkipWithError("cannot create the stream");
  std::int64_t stamp = 0;
  for (auto _ : state) {
    sim::Loan loan = stream.writer->loan();
    const auto result = decoder->decode(bytes_of(yuyv), loan.bytes());
    benchmark::DoNotOptimize(std::move(loan).commit(result.size, ++stamp));
  }
}

// The same decoder into ordinary heap memory: separates the decode from the shared-memory slot.
void YuyvToBgr_SimDecoderIntoHeap(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  cv::Mat yuyv(h, w, CV_8UC2);
  cv::randu(yuyv, 0, 255);
  auto decoder = FrameDecoder::create(make_layout(static_cast<std::uint32_t>(w),
                                                  static_cast<std::uint32_t>(h), sim::PixelFormat::yuyv),
                                      sim::imaging::OutputFormat::bgr8);
  std::vector<std::byte> heap(decoder->output_layout().frame_bytes());
  for (auto _ : state) {
    benchmark::DoNotOptimize(decoder->decode(bytes_of(yuyv), heap));
  }
}

void YuyvToBgr_OpenCvFreshMat(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  cv::Mat yuyv(h, w, CV_8UC2);
  cv::randu(yuyv, 0, 255);
  for (auto _ : state) {
    cv::Mat bgr;
    cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
    benchmark::DoNotOptimize(bgr.data);
  }
}

void MjpegToBgr_Sim(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  const auto jpeg = jpeg_422(scene(w, h));
  auto decoder = FrameDecoder::create(make_layout(static_cast<std::uint32_t>(w),
                                                  static_cast<std::uint32_t>(h), sim::PixelFormat::mjpeg),
                                      sim::imaging::OutputFormat::bgr8);
  Stream stream(decoder->output_layout());
  if (!stream.writer) return state.SkipWithError("cannot create the stream");
  const std::span<const std::byte> input(reinterpret_cast<const std::byte*>(jpeg.data()), jpeg.size());
  std::int64_t stamp = 0;
  for (auto _ : state) {
    sim::Loan loan = stream.writer->loan();
    const auto result = decoder->decode(input, loan.bytes());
    if (result.status != sim::imaging::DecodeStatus::ok) return state.SkipWithError("decode failed");
    benchmark::DoNotOptimize(std::move(loan).commit(result.size, ++stamp));
  }
  state.counters["jpeg_kB"] = static_cast<double>(jpeg.size()) / 1000.0;
}

void MjpegToBgr_ImdecodeCopy(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const int h = static_cast<int>(state.range(1));
  const auto jpeg = jpeg_422(scene(w, h));
  const cv::Mat encoded(1, static_cast<int>(jpeg.size()), CV_8UC1, const_cast<unsigned char*>(jpeg.data()));
  Stream stream(make_layout(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h),
                            sim::PixelFormat::bgr8));
  if (!stream.writer) return state.SkipWithError("cannot create the stream");
  std::int64_t stamp = 0;
  for (auto _ : state) {
    const cv::Mat bgr = cv::imdecode(encoded, cv::IMREAD_COLOR);
    sim::Loan loan = stream.writer->loan();
    std::memcpy(loan.bytes().data(), bgr.data, bgr.total() * bgr.elemSize());
    benchmark::DoNotOptimize(std::move(loan).commit(bgr.total() * bgr.elemSize(), ++stamp));
  }
}

#define SIM_CAMERA_SIZES ->Args({640, 480})->Args({1920, 1200})->Unit(benchmark::kMillisecond)
BENCHMARK(YuyvToBgr_Sim) SIM_CAMERA_SIZES;
BENCHMARK(YuyvToBgr_SimDecoderIntoHeap) SIM_CAMERA_SIZES;
BENCHMARK(YuyvToBgr_OpenCvFreshMat) SIM_CAMERA_SIZES;
BENCHMARK(MjpegToBgr_Sim) SIM_CAMERA_SIZES;
BENCHMARK(MjpegToBgr_ImdecodeCopy) SIM_CAMERA_SIZES;

// Keeps each benchmark's time (the median when --benchmark_repetitions is given) so the ratios
// can be printed after the usual table.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& run : runs) {
      if (run.error_occurred) continue;
      const std::string name = run.run_name.str();
      const Times value{run.GetAdjustedRealTime(), run.GetAdjustedCPUTime()};
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        medians[name] = value;
      } else if (run.run_type == Run::RT_Iteration) {
        times[name] = value;
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  struct Times {
    double real;
    double cpu;  // of the benchmark thread only: OpenCV's worker threads are not counted
  };
  const std::map<std::string, Times>& result() const { return medians.empty() ? times : medians; }
  std::map<std::string, Times> times;
  std::map<std::string, Times> medians;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  std::printf("\nRatios of wall time (SIM path / OpenCV path; < 1 means SIM is faster), OpenCV "
              "threads: %d. On a loaded machine trust the CPU-time ratio of the single-threaded "
              "MJPEG paths more.\n", cv::getNumThreads());
  for (const char* size : {"640/480", "1920/1200"}) {
    for (const auto& [ours, theirs] :
         {std::pair{"YuyvToBgr_Sim", "YuyvToBgr_OpenCvFreshMat"},
          std::pair{"YuyvToBgr_SimDecoderIntoHeap", "YuyvToBgr_OpenCvFreshMat"},
          std::pair{"MjpegToBgr_Sim", "MjpegToBgr_ImdecodeCopy"}}) {
      const auto& times = reporter.result();
      const auto a = times.find(std::string(ours) + "/" + size);
      const auto b = times.find(std::string(theirs) + "/" + size);
      if (a == times.end() || b == times.end()) continue;
      const double ratio = a->second.real / b->second.real;
      // Both readings of "N % faster" are printed: the speed ratio and the time saved.
      std::printf("  %-10s %-28s vs %-25s %.2f  (%.2fx the speed, %.0f%% %s time; CPU-time ratio "
                  "%.2f)\n",
                  size, ours, theirs, ratio, 1.0 / ratio, 100.0 * std::abs(1.0 - ratio),
                  ratio <= 1.0 ? "less" : "more", a->second.cpu / b->second.cpu);
    }
  }
  benchmark::Shutdown();
  return 0;
}
