// dynamic benchmarks: each stage of the dynamic-region detector and the whole detector on real 752x480 EuRoC
// frames (rectified), single-threaded (bench_main sets cv::setNumThreads(1)).
//   *Static*      consecutive EuRoC frames as they are (nothing moves in V1_01's first seconds);
//   *ThreePeople* the same frames with three person-sized textured boards pasted into both images at
//                 consistent disparities (a stereo-correct occlusion of the real background), moving
//                 independently of the camera from frame to frame.
// Data: env AGVSLAM_SHARED_DIR, else the configured shared folder; a case whose data is missing reports an error.
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/io/dataset.h"

namespace {
namespace fs = std::filesystem;
using namespace agvslam::dynamic;

constexpr int kSequenceLength = 24;

struct BenchData {
  agvslam::StereoCalibration calibration;
  std::vector<agvslam::StereoFrame> frames;  // EuRoC frames 30.. rectified
  std::vector<agvslam::StereoFrame> people;  // the same with three moving boards
  std::string error;
};

std::string dynamic_bench_data(const std::string& rel) {
  const char* env = std::getenv("AGVSLAM_SHARED_DIR");
  const std::string base = (env && *env) ? env : AGVSLAM_SHARED_DIR_DEFAULT;
  return (fs::path(base) / "data" / rel).string();
}

// A board of w x h px at image position (x, y) and disparity d: pasted at x in the left, x - d in the right.
void paste_board(agvslam::StereoFrame& f, const cv::Mat& texture, cv::Point tl, double disparity_px) {
  const cv::Rect image(cv::Point(0, 0), f.left.size());
  const cv::Rect in_left = cv::Rect(tl, texture.size()) & image;
  if (in_left.empty()) return;
  texture(cv::Rect(in_left.tl() - tl, in_left.size())).copyTo(f.left(in_left));
  // Right image: sub-pixel shift of the board by -d.
  cv::Mat shifted;
  const int d_int = static_cast<int>(std::floor(disparity_px));
  const double frac = disparity_px - d_int;
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, -frac, 0, 1, 0);
  cv::warpAffine(texture, shifted, M, texture.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const cv::Point tl_r(tl.x - d_int, tl.y);
  const cv::Rect in_right = cv::Rect(tl_r, texture.size()) & image;
  if (in_right.empty()) return;
  shifted(cv::Rect(in_right.tl() - tl_r, in_right.size())).copyTo(f.right(in_right));
}

cv::Mat board_texture(cv::Size size, double mean, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat coarse(size.height / 6 + 2, size.width / 6 + 2, CV_32F);
  rng.fill(coarse, cv::RNG::UNIFORM, -60.0, 60.0);
  cv::Mat up, out;
  cv::resize(coarse, up, size, 0, 0, cv::INTER_CUBIC);
  up.convertTo(out, CV_8U, 1.0, mean);
  return out;
}

const BenchData& bench_data() {
  static BenchData data;
  static bool loaded = false;
  if (loaded) return data;
  loaded = true;
  const std::string root = dynamic_bench_data("euroc_v101_f000-094");
  if (!fs::exists(root)) {
    data.error = "shared data not found: " + root + " (set AGVSLAM_SHARED_DIR)";
    return data;
  }
  try {
    const auto level = spdlog::get_level();
    spdlog::set_level(spdlog::level::err);
    const agvslam::io::EurocDataset dataset(root);
    spdlog::set_level(level);
    data.calibration = dataset.calibration();
    for (int i = 0; i < kSequenceLength; ++i) data.frames.push_back(dataset.frame(30 + static_cast<std::size_t>(i)));
  } catch (const agvslam::InputError& e) {
    data.error = e.what();
    return data;
  }
  // Three people: 60x180, 50x160, 70x200 px boards at disparities 16, 12, 20 px (3.0, 4.0, 2.4 m for bf 48),
  // walking left, right, and left while coming closer.
  const cv::Mat tex[3] = {board_texture({60, 180}, 160, 1), board_texture({50, 160}, 70, 2),
                          board_texture({70, 200}, 190, 3)};
  for (int i = 0; i < kSequenceLength; ++i) {
    agvslam::StereoFrame f = data.frames[static_cast<std::size_t>(i)];
    f.left = f.left.clone();
    f.right = f.right.clone();
    paste_board(f, tex[0], {420 - 5 * i, 150}, 16.0);
    paste_board(f, tex[1], {150 + 4 * i, 170}, 12.0);
    paste_board(f, tex[2], {600 - 3 * i, 120 + i / 2}, 20.0 + 0.25 * i);
    data.people.push_back(f);
  }
  return data;
}

const BenchData* data_or_skip(benchmark::State& state) {
  const BenchData& d = bench_data();
  if (!d.error.empty()) {
    state.SkipWithError(d.error.c_str());
    return nullptr;
  }
  return &d;
}

void BM_DynamicQuadtreeFast(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  QuadtreeFast fast;
  std::vector<Corner> corners;
  QuadtreeStats stats;
  for (auto _ : state) {
    fast.detect(d->frames[0].left, corners, &stats);
    benchmark::DoNotOptimize(corners.data());
  }
  state.counters["corners"] = static_cast<double>(corners.size());
  state.counters["candidates"] = stats.candidates;
}
BENCHMARK(BM_DynamicQuadtreeFast)->Unit(benchmark::kMillisecond);

// The two ways of finding the quadtree's candidates (the same corners): arg 0 = EuRoC frame 0 (plain walls: most
// cells weak), 1 = a textured 752x480 board (few weak cells, like the simulator's warehouse); arg 1 = single pass
// (FAST at 7 everywhere) or two passes (FAST at 20, then at 7 where no cell corner passes 20).
void BM_DynamicQuadtreeFastExtraction(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  const cv::Mat image = state.range(0) == 0 ? d->frames[0].left : board_texture({752, 480}, 128, 5);
  QuadtreeFast fast;
  fast.set_extraction(state.range(1) == 0 ? QuadtreeFast::Extraction::kSinglePass : QuadtreeFast::Extraction::kTwoPass);
  std::vector<Corner> corners;
  QuadtreeStats stats;
  for (auto _ : state) {
    fast.detect(image, corners, &stats);
    benchmark::DoNotOptimize(corners.data());
  }
  state.counters["candidates"] = stats.candidates;
  state.counters["weak_cells"] = stats.weak_cells;
}
BENCHMARK(BM_DynamicQuadtreeFastExtraction)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

void BM_DynamicLkPyramid(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  LkTracker tracker;
  std::vector<cv::Mat> pyramid;
  for (auto _ : state) {
    tracker.build_pyramid(d->frames[1].left, pyramid);
    benchmark::DoNotOptimize(pyramid.data());
  }
}
BENCHMARK(BM_DynamicLkPyramid)->Unit(benchmark::kMillisecond);

// Forward + backward LK of the 300 quadtree corners of frame 0 into frame 1.
void BM_DynamicLkTrack(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  LkTracker tracker;
  QuadtreeFast fast;
  std::vector<Corner> corners;
  fast.detect(d->frames[0].left, corners);
  std::vector<cv::Point2f> prev, cur;
  for (const Corner& c : corners) prev.push_back(c.pt);
  std::vector<cv::Mat> p0, p1;
  tracker.build_pyramid(d->frames[0].left, p0);
  tracker.build_pyramid(d->frames[1].left, p1);
  std::vector<uint8_t> ok;
  for (auto _ : state) {
    tracker.track(p0, p1, prev, cur, ok);
    benchmark::DoNotOptimize(cur.data());
  }
  int tracked = 0;
  for (uint8_t o : ok) tracked += o;
  state.counters["points"] = static_cast<double>(prev.size());
  state.counters["tracked"] = tracked;
}
BENCHMARK(BM_DynamicLkTrack)->Unit(benchmark::kMillisecond);

// F by RANSAC + eq. 1-3 on 300 tracks, and the PnP depth test on the same tracks.
struct Tracks {
  std::vector<cv::Point2f> prev, cur;
  std::vector<float> d_prev, d_cur;
  std::vector<uint8_t> ok;
};

Tracks make_tracks(const BenchData& d) {
  Tracks t;
  LkTracker tracker;
  QuadtreeFast fast;
  std::vector<Corner> corners;
  fast.detect(d.frames[0].left, corners);
  for (const Corner& c : corners) t.prev.push_back(c.pt);
  std::vector<cv::Mat> p0, p1;
  tracker.build_pyramid(d.frames[0].left, p0);
  tracker.build_pyramid(d.frames[1].left, p1);
  tracker.track(p0, p1, t.prev, t.cur, t.ok);
  agvslam::stereo::SparseStereoMatcher matcher;
  matcher.match(d.frames[0].left, d.frames[0].right, t.prev, t.d_prev);
  matcher.match(d.frames[1].left, d.frames[1].right, t.cur, t.d_cur);
  return t;
}

void BM_DynamicEpipolarTest(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  const Tracks t = make_tracks(*d);
  EpipolarTest test;
  EpipolarResult result;
  for (auto _ : state) {
    test.run(t.prev, t.cur, t.ok, t.d_cur, result);
    benchmark::DoNotOptimize(result.dynamic.data());
  }
  int dynamic = 0;
  for (uint8_t v : result.dynamic) dynamic += v;
  state.counters["dynamic"] = dynamic;
  state.counters["inliers"] = result.inliers;
}
BENCHMARK(BM_DynamicEpipolarTest)->Unit(benchmark::kMillisecond);

void BM_DynamicDepthTest(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  const Tracks t = make_tracks(*d);
  DepthConsistencyTest test;
  DepthTestResult result;
  for (auto _ : state) {
    test.run(d->calibration.left, d->calibration.bf(), t.prev, t.d_prev, t.cur, t.d_cur, t.ok, result);
    benchmark::DoNotOptimize(result.dynamic.data());
  }
  int dynamic = 0;
  for (uint8_t v : result.dynamic) dynamic += v;
  state.counters["dynamic"] = dynamic;
  state.counters["inliers"] = result.inliers;
}
BENCHMARK(BM_DynamicDepthTest)->Unit(benchmark::kMillisecond);

// The per-ROI stages on a person-sized ROI (110x250 px) around the first pasted board.
struct RoiInput {
  cv::Rect roi{390, 120, 110, 250};
  cv::Mat grey, disparity_px;
};

RoiInput make_roi(const BenchData& d) {
  RoiInput in;
  agvslam::stereo::StereoSgbm sgbm;
  sgbm.compute_roi(d.people[0].left, d.people[0].right, in.roi, in.disparity_px);
  in.grey = d.people[0].left(in.roi).clone();
  return in;
}

void BM_DynamicSlic(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  const RoiInput in = make_roi(*d);
  Slic slic;
  cv::Mat labels;
  SlicStats stats;
  const bool incremental = state.range(0) != 0;
  for (auto _ : state) {
    slic.segment(in.grey, labels, incremental, &stats);
    benchmark::DoNotOptimize(labels.data);
  }
  state.SetLabel(incremental ? "incremental" : "plain");
  state.counters["evaluations"] = static_cast<double>(stats.distance_evaluations);
  state.counters["superpixels"] = stats.superpixels;
  state.counters["iterations"] = stats.iterations;
}
BENCHMARK(BM_DynamicSlic)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_DynamicPlanesAndBoundaries(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  const RoiInput in = make_roi(*d);
  Slic slic;
  cv::Mat labels;
  const int count = slic.segment(in.grey, labels);
  std::vector<DisparityPlane> planes;
  SuperpixelGraph graph;
  const PlaneFitConfig plane_config;
  const BoundaryConfig boundary_config;
  for (auto _ : state) {
    fit_superpixel_planes(labels, count, in.disparity_px, in.roi.tl(), plane_config, planes);
    graph.build(labels, count, in.roi.tl());
    label_boundaries(graph, planes, boundary_config);
    benchmark::DoNotOptimize(graph.boundaries().data());
  }
  int occlusions = 0;
  for (const auto& b : graph.boundaries()) occlusions += is_occlusion(b.type);
  state.counters["superpixels"] = count;
  state.counters["boundaries"] = static_cast<double>(graph.boundaries().size());
  state.counters["occlusions"] = occlusions;
}
BENCHMARK(BM_DynamicPlanesAndBoundaries)->Unit(benchmark::kMillisecond);

// The sides of an outline re-decided at full resolution (edge_refine.h): a 70 x 200 px board pasted at d = 30 px
// (1.6 m, well in front of the room) into the first frame, at x 300, y 120; the ROI's SGBM disparity; the outline
// given is the board's rectangle widened by 3 px at either side, as SGBM's 5x5 window fattens it. Counters: the
// pixels the refinement removed (ideally 2 x 3 x 200 = 1200) and added (ideally 0).
void BM_DynamicEdgeRefine(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  agvslam::StereoFrame f = d->frames[0];
  f.left = f.left.clone();
  f.right = f.right.clone();
  const cv::Rect board(300, 120, 70, 200);
  paste_board(f, board_texture(board.size(), 120, 4), board.tl(), 30.0);
  const cv::Rect roi(board.x - 30, board.y - 30, board.width + 60, board.height + 60);
  cv::Mat disparity_px;
  agvslam::stereo::StereoSgbm sgbm;
  sgbm.compute_roi(f.left, f.right, roi, disparity_px);
  cv::Mat outline(roi.size(), CV_8UC1, cv::Scalar(0)), mask;
  outline(cv::Rect(board.x - 3 - roi.x, board.y - roi.y, board.width + 6, board.height)).setTo(255);
  EdgeRefiner refiner;
  EdgeRefineStats stats;
  for (auto _ : state) {
    outline.copyTo(mask);
    stats = refiner.refine(f.left, f.right, roi, disparity_px, mask);
    benchmark::DoNotOptimize(mask.data);
  }
  state.counters["sides"] = stats.sides;
  state.counters["moved"] = stats.moved;
  state.counters["removed_px"] = stats.pixels_removed;
  state.counters["added_px"] = stats.pixels_added;
}
BENCHMARK(BM_DynamicEdgeRefine)->Unit(benchmark::kMillisecond);

// The whole detector, one new frame per iteration (the sequence repeats; a reset at the wrap keeps every
// measured call a "consecutive frame" call).
void run_detector(benchmark::State& state, const std::vector<agvslam::StereoFrame>& frames,
                  const agvslam::StereoCalibration& calibration) {
  DynamicDetector detector(calibration);
  DetectorResult result;
  detector.detect(frames[0], result);
  std::size_t i = 1;
  StageTimings sum;
  int calls = 0, rois = 0, dynamic_points = 0;
  double mask_px = 0;
  // Each frame's wall time: the figure is the per-frame median, which the mean per iteration that
  // Google Benchmark reports can hide (frames differ in how many people they hold).
  std::vector<double> frame_ms;
  for (auto _ : state) {
    if (i == frames.size()) {
      state.PauseTiming();
      detector.reset();
      detector.detect(frames[0], result);
      i = 1;
      state.ResumeTiming();
    }
    const auto t0 = std::chrono::steady_clock::now();
    detector.detect(frames[i++], result);
    frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const StageTimings& t = result.timings;
    sum.pyramid_ms += t.pyramid_ms;
    sum.tracking_ms += t.tracking_ms;
    sum.point_disparity_ms += t.point_disparity_ms;
    sum.epipolar_ms += t.epipolar_ms;
    sum.depth_test_ms += t.depth_test_ms;
    sum.multiframe_ms += t.multiframe_ms;
    sum.densify_ms += t.densify_ms;
    sum.grouping_ms += t.grouping_ms;
    sum.roi_disparity_ms += t.roi_disparity_ms;
    sum.slic_ms += t.slic_ms;
    sum.planes_ms += t.planes_ms;
    sum.boundaries_ms += t.boundaries_ms;
    sum.regions_ms += t.regions_ms;
    sum.motion_carve_ms += t.motion_carve_ms;
    sum.band_ms += t.band_ms;
    sum.features_ms += t.features_ms;
    sum.total_ms += t.total_ms;
    ++calls;
    rois += static_cast<int>(result.rois.size());
    dynamic_points += result.dynamic_point_count();
    mask_px += result.mask.pixel_count();
  }
  if (calls == 0) return;
  const double n = calls;
  state.counters["pyramid_ms"] = sum.pyramid_ms / n;
  state.counters["tracking_ms"] = sum.tracking_ms / n;
  state.counters["point_disp_ms"] = sum.point_disparity_ms / n;
  state.counters["epipolar_ms"] = sum.epipolar_ms / n;
  state.counters["depth_ms"] = sum.depth_test_ms / n;
  state.counters["multiframe_ms"] = sum.multiframe_ms / n;
  state.counters["densify_ms"] = sum.densify_ms / n;
  state.counters["grouping_ms"] = sum.grouping_ms / n;
  state.counters["roi_disp_ms"] = sum.roi_disparity_ms / n;
  state.counters["slic_ms"] = sum.slic_ms / n;
  state.counters["planes_ms"] = sum.planes_ms / n;
  state.counters["boundaries_ms"] = sum.boundaries_ms / n;
  state.counters["regions_ms"] = sum.regions_ms / n;
  state.counters["motion_carve_ms"] = sum.motion_carve_ms / n;
  state.counters["band_ms"] = sum.band_ms / n;
  state.counters["features_ms"] = sum.features_ms / n;
  state.counters["rois"] = rois / n;
  state.counters["dyn_points"] = dynamic_points / n;
  state.counters["mask_px"] = mask_px / n;
  std::sort(frame_ms.begin(), frame_ms.end());
  state.counters["frame_median_ms"] = frame_ms[frame_ms.size() / 2];
  state.counters["frame_p95_ms"] = frame_ms[std::min(frame_ms.size() - 1, frame_ms.size() * 95 / 100)];
}

void BM_DynamicDetectorStatic(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  run_detector(state, d->frames, d->calibration);
}
BENCHMARK(BM_DynamicDetectorStatic)->Unit(benchmark::kMillisecond);

void BM_DynamicDetectorThreePeople(benchmark::State& state) {
  const BenchData* d = data_or_skip(state);
  if (!d) return;
  run_detector(state, d->people, d->calibration);
}
BENCHMARK(BM_DynamicDetectorThreePeople)->Unit(benchmark::kMillisecond);

}  // namespace
