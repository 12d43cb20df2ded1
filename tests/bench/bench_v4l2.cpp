// V4L2 camera path on the host (no device): per-frame cost of converting what a camera delivers into grey
// (GREY copy, YUYV luma, MJPEG through libv4lconvert), the side-by-side split, the frame hash, pairing.
#include <benchmark/benchmark.h>

#include <deque>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/drivers/v4l2/pairing.h"
#include "agvslam/drivers/v4l2/pixel_convert.h"

namespace v4l2 = agvslam::drivers::v4l2;

namespace {
constexpr int kW = 752, kH = 480;

void BM_V4l2GreyCopy(benchmark::State& state) {
  std::vector<uint8_t> src(static_cast<std::size_t>(kW) * kH, 77);
  cv::Mat grey(kH, kW, CV_8UC1);
  for (auto _ : state) {
    v4l2::grey_to_grey(src.data(), kW, grey);
    benchmark::DoNotOptimize(grey.data);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * kW * kH);
}
BENCHMARK(BM_V4l2GreyCopy)->Unit(benchmark::kMicrosecond);

void BM_V4l2YuyvToGrey(benchmark::State& state) {
  std::vector<uint8_t> src(static_cast<std::size_t>(kW) * kH * 2);
  for (std::size_t i = 0; i < src.size(); ++i) src[i] = static_cast<uint8_t>(i * 31);
  cv::Mat grey(kH, kW, CV_8UC1);
  for (auto _ : state) {
    v4l2::yuyv_to_grey(src.data(), 2 * kW, grey);
    benchmark::DoNotOptimize(grey.data);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * kW * kH * 2);
}
BENCHMARK(BM_V4l2YuyvToGrey)->Unit(benchmark::kMicrosecond);

// MJPEG 752x480 (quality 90, OpenCV's 4:2:0) to grey with libv4lconvert: what a camera sending MJPEG costs per
// eye. The image is smoothed noise, about as hard for the entropy decoder as a textured scene.
void BM_V4l2MjpegToGrey(benchmark::State& state) {
  cv::Mat grey(kH, kW, CV_8UC1), bgr;
  cv::randu(grey, 0, 256);
  cv::GaussianBlur(grey, grey, cv::Size(5, 5), 1.5);
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
  v4l2::MjpegDecoder dec;
  cv::Mat out(kH, kW, CV_8UC1);
  for (auto _ : state) {
    if (!dec.decode(jpeg.data(), jpeg.size(), out)) state.SkipWithError(dec.error().c_str());
    benchmark::DoNotOptimize(out.data);
  }
  state.counters["jpeg_kB"] = static_cast<double>(jpeg.size()) / 1024.0;
}
BENCHMARK(BM_V4l2MjpegToGrey)->Unit(benchmark::kMillisecond);

void BM_V4l2SideBySideSplit(benchmark::State& state) {
  cv::Mat sbs(kH, 2 * kW, CV_8UC1);
  cv::randu(sbs, 0, 256);
  cv::Mat l, r;
  for (auto _ : state) {
    v4l2::split_side_by_side(sbs, l, r);
    benchmark::DoNotOptimize(l.data);
  }
}
BENCHMARK(BM_V4l2SideBySideSplit)->Unit(benchmark::kMicrosecond);

void BM_V4l2ImageHash(benchmark::State& state) {
  cv::Mat grey(kH, kW, CV_8UC1);
  cv::randu(grey, 0, 256);
  for (auto _ : state) benchmark::DoNotOptimize(v4l2::image_hash(grey));
}
BENCHMARK(BM_V4l2ImageHash)->Unit(benchmark::kMicrosecond);

void BM_V4l2PairerPerPair(benchmark::State& state) {
  v4l2::TimestampPairer p(5000000, 4);
  std::deque<int> released;
  int64_t t = 0;
  for (auto _ : state) {
    t += 50000000;
    p.push_left({t, 0, 0}, released);
    p.push_right({t + 1000000, 0, 1}, released);
    benchmark::DoNotOptimize(p.pop(released));
  }
}
BENCHMARK(BM_V4l2PairerPerPair);
}  // namespace
