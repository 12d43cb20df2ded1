// agvslam-dynamic: runs the dynamic-region detector (paper 004, III.A-B) over a stereo sequence.
//
//   agvslam-dynamic --dataset DIR --out DIR [--json FILE] [--frames A:B] [--params-dynamic params/dynamic.yaml]
//                   [--params-stereo params/stereo.yaml] [--calib FILE] [--overlay-every N]
//                   [--min-object-pixels N] [--min-iou X] [--semantic MODEL|off] [--params-semantic FILE]
//
// --semantic MODEL adds the semantic stage (agvslam/semantic/semantic_masker.h, params/semantic.yaml): segmented
// movable objects that move are fused with the detector's mask and scored with it; here it waits for every
// segmentation (fusion.synchronous), so the scores do not depend on timing. A model that cannot be loaded leaves
// the detector alone, with a warning.
//
// Writes <out>/mask/NNNNNN.png (8-bit, 255 = dynamic) for every frame, and every N-th frame an overlay
// <out>/overlay/NNNNNN.png with four panels like the paper's Figs. 3, 5, 7 and 8: (a) SGBM disparity of the
// whole frame, (b) tracked points (green static, red dynamic, orange densified dynamic) and the dynamic ROIs
// (yellow), (c) the ROIs' superpixels with occlusion boundaries in red and hinges in blue (tinted green where the
// photometric check found them moving with the background, magenta where they moved otherwise), (d) the mask
// and regions (red rectangles) against the ground truth where the dataset has one (green: correct, red: false,
// blue: missed pixels).
// Where the dataset has mask_0/ (the simulator), each frame after the first is scored as the paper does
// (eqs. 12-14, objects matched by IoU >= 0.5; each detector region is one detected object; with instance_0/ each
// ground-truth object is its own visible pixels, also where objects overlap; see agvslam/eval/detection_scoring.h).
// The first line of stdout is `PRECISION <p> RECALL <r> IOU <iou>` (fractions; nan without ground truth),
// followed by the counts, regions per frame and per-stage median/p95 times. Exit status: 0 on success, 2 on bad
// input (the message names the option, file or folder), 1 on any other failure.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/clock.h"
#include "agvslam/core/error.h"
#include "agvslam/core/stats.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/dynamic/median.h"
#include "agvslam/eval/detection_scoring.h"
#include "agvslam/eval/object_motion.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/objects_io.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/semantic/semantic_masker.h"
#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/stereo_config.h"
#include "tool_main.h"

namespace {

namespace fs = std::filesystem;
using agvslam::InputError;
using agvslam::Series;
using agvslam::thread_cpu_ms;
namespace dyn = agvslam::dynamic;
namespace eval = agvslam::eval;

struct Options {
  std::string dataset, out_dir, json_path, frames, params_dynamic, params_stereo, calib;
  std::string semantic = "off", params_semantic;
  int overlay_every = 10;
  int opencv_threads = 1;
  int min_object_pixels = 400;
  double min_iou = 0.5;
  bool json_points = false;
  bool dump_rois = false;
};

std::string frame_name(std::size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06zu.png", i);
  return buf;
}

void write_png(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  } catch (const cv::Exception& e) {
    throw InputError("--out", path, std::string("could not write the image: ") + e.what());
  }
  if (!ok) throw InputError("--out", path, "could not write the image (disk full or not writable?)");
}

// ---------------------------------------------------------------------------------------------------------------
// Overlays

cv::Mat grey_to_bgr(const cv::Mat& grey) {
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

void label(cv::Mat& panel, const std::string& text) {
  cv::rectangle(panel, cv::Rect(0, 0, panel.cols, 26), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(panel, text, cv::Point(8, 19), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

cv::Mat disparity_panel(const cv::Mat& disparity_px, double max_disparity_px) {
  cv::Mat scaled, colour;
  disparity_px.convertTo(scaled, CV_8U, 255.0 / std::max(1.0, max_disparity_px));
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  colour.setTo(cv::Scalar(0, 0, 0), disparity_px <= 0);
  return colour;
}

cv::Mat points_panel(const cv::Mat& left, const dyn::DetectorResult& r) {
  cv::Mat panel = grey_to_bgr(left);
  for (const auto& roi : r.rois) cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 2);
  for (const auto& p : r.points) {
    if (!p.tracked) continue;
    cv::Scalar colour =
        p.dynamic ? (p.densified ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 0, 255)) : cv::Scalar(0, 200, 0);
    cv::line(panel, p.prev_px, p.cur_px, colour, 1, cv::LINE_AA);
    cv::circle(panel, p.cur_px, p.dynamic ? 3 : 2, colour, p.dynamic ? cv::FILLED : 1, cv::LINE_AA);
  }
  // The left band's seeds (cyan, band_segmenter.h) and the outlines of its regions (magenta).
  for (const auto& region : r.band.regions) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(region.mask.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE, region.rect.tl());
    cv::drawContours(panel, contours, -1, cv::Scalar(255, 0, 255), 1);
  }
  for (const auto& seed : r.band.seeds) {
    cv::line(panel, seed.prev_px, seed.cur_px, cv::Scalar(255, 255, 0), 1, cv::LINE_AA);
    cv::circle(panel, seed.cur_px, 3, cv::Scalar(255, 255, 0), cv::FILLED, cv::LINE_AA);
  }
  return panel;
}

cv::Mat superpixel_panel(const cv::Mat& left, const dyn::DetectorResult& r) {
  cv::Mat panel = grey_to_bgr(left);
  for (const auto& roi : r.rois) {
    if (roi.labels.empty() && !roi.outline.empty()) {
      // mask_mode disparity: the ROI's disparity (grey: none) with the object's outline in red.
      const cv::Rect area = roi.roi & cv::Rect(cv::Point(0, 0), panel.size());
      cv::Mat disp = disparity_panel(roi.disparity_px, std::max(8.0, 2.0 * roi.mean_disparity_px));
      disp.setTo(cv::Scalar(90, 90, 90), roi.disparity_px <= 0);
      cv::addWeighted(panel(area), 0.4, disp(cv::Rect(area.tl() - roi.roi.tl(), area.size())), 0.6, 0, panel(area));
      // Red: a dynamic region; orange: an outline the checks dropped (its verdict is written above the ROI).
      const bool kept = roi.outline_verdict == dyn::OutlineVerdict::kKept;
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(roi.outline.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE, roi.roi.tl());
      cv::drawContours(panel, contours, -1, kept ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 140, 255), 1);
      if (!kept) {
        cv::putText(panel, dyn::to_string(roi.outline_verdict), roi.roi.tl() + cv::Point(2, -4),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 140, 255), 1, cv::LINE_AA);
      }
      for (int k : roi.points)
        cv::circle(panel, r.points[static_cast<std::size_t>(k)].cur_px, 2, cv::Scalar(255, 255, 255), cv::FILLED);
      cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 1);
      continue;
    }
    if (roi.labels.empty()) continue;
    std::map<std::pair<int, int>, dyn::BoundaryType> types;
    for (const auto& b : roi.boundaries) types[{b.i, b.j}] = b.type;
    auto colour_of = [&](int a, int b) {
      const auto it = types.find({std::min(a, b), std::max(a, b)});
      const dyn::BoundaryType t = it == types.end() ? dyn::BoundaryType::kUnknown : it->second;
      if (dyn::is_occlusion(t)) return cv::Vec3b(0, 0, 255);
      if (t == dyn::BoundaryType::kHinge) return cv::Vec3b(255, 120, 0);
      if (t == dyn::BoundaryType::kCoplanar) return cv::Vec3b(255, 255, 255);
      return cv::Vec3b(160, 160, 160);
    };
    const cv::Mat& labels = roi.labels;
    // Photometric check: green tint = moves with the background, magenta = moved differently.
    if (!roi.motion.empty()) {
      for (int y = 0; y < labels.rows; ++y) {
        const int* row = labels.ptr<int>(y);
        for (int x = 0; x < labels.cols; ++x) {
          const int k = row[x];
          if (k < 0 || static_cast<std::size_t>(k) >= roi.motion.size() ||
              roi.motion[static_cast<std::size_t>(k)].apparent_motion_px < 0)
            continue;
          const cv::Point p(roi.roi.x + x, roi.roi.y + y);
          if (p.x >= panel.cols || p.y >= panel.rows) continue;
          cv::Vec3b& px = panel.at<cv::Vec3b>(p);
          const cv::Vec3b tint = roi.motion[static_cast<std::size_t>(k)].moves_with_background ? cv::Vec3b(0, 255, 0)
                                                                                               : cv::Vec3b(255, 0, 255);
          for (int c = 0; c < 3; ++c) px[c] = static_cast<uint8_t>((px[c] * 2 + tint[c]) / 3);
        }
      }
    }
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      const int* below = y + 1 < labels.rows ? labels.ptr<int>(y + 1) : nullptr;
      for (int x = 0; x < labels.cols; ++x) {
        int other = -1;
        if (x + 1 < labels.cols && row[x + 1] != row[x])
          other = row[x + 1];
        else if (below && below[x] != row[x])
          other = below[x];
        if (other < 0) continue;
        const cv::Point p(roi.roi.x + x, roi.roi.y + y);
        if (p.x < panel.cols && p.y < panel.rows) panel.at<cv::Vec3b>(p) = colour_of(row[x], other);
      }
    }
    cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 1);
  }
  return panel;
}

cv::Mat regions_panel(const cv::Mat& left, const dyn::DetectorResult& r, const cv::Mat& gt_mask) {
  cv::Mat panel = grey_to_bgr(left);
  auto tint = [&](const cv::Mat& where, const cv::Scalar& colour) {
    cv::Mat solid(panel.size(), CV_8UC3, colour), blended;
    cv::addWeighted(panel, 0.45, solid, 0.55, 0, blended);
    blended.copyTo(panel, where);
  };
  if (gt_mask.empty()) {
    tint(r.mask.image, cv::Scalar(0, 0, 255));
  } else {  // green: detected and moving; red: detected but static; blue: moving but missed
    tint(r.mask.image & gt_mask, cv::Scalar(0, 200, 0));
    tint(r.mask.image & ~gt_mask, cv::Scalar(0, 0, 255));
    tint(~r.mask.image & gt_mask, cv::Scalar(255, 0, 0));
  }
  for (const auto& rect : r.mask.regions) cv::rectangle(panel, rect, cv::Scalar(0, 0, 255), 1);
  return panel;
}

cv::Mat compose_overlay(const cv::Mat& left, const cv::Mat& right, const dyn::DetectorResult& r, const cv::Mat& gt_mask,
                        agvslam::stereo::StereoSgbm& sgbm) {
  cv::Mat disparity_px;
  sgbm.compute(left, right, disparity_px);
  cv::Mat a = disparity_panel(disparity_px, sgbm.config().max_disparity());
  cv::Mat b = points_panel(left, r);
  cv::Mat c = superpixel_panel(left, r);
  cv::Mat d = regions_panel(left, r, gt_mask);
  label(a, "(a) SGBM disparity (whole frame, for display)");
  label(b, "(b) tracks: green static, red dynamic; yellow: dynamic ROIs");
  label(c, r.rois.empty() || !r.rois.front().labels.empty()
               ? "(c) red occlusion, blue hinge; tint: green static, magenta moved"
               : "(c) ROI disparity; outline: red region, orange dropped");
  label(d, gt_mask.empty() ? "(d) dynamic mask and regions (red)" : "(d) mask: green correct, red false, blue missed");
  cv::Mat top, bottom, all;
  cv::hconcat(a, b, top);
  cv::hconcat(c, d, bottom);
  cv::vconcat(top, bottom, all);
  return all;
}

// ---------------------------------------------------------------------------------------------------------------
// Timing

std::vector<std::pair<std::string, double>> stage_values(const dyn::StageTimings& t) {
  return {{"pyramid", t.pyramid_ms},
          {"tracking", t.tracking_ms},
          {"point_disparity", t.point_disparity_ms},
          {"epipolar", t.epipolar_ms},
          {"depth_test", t.depth_test_ms},
          {"multiframe", t.multiframe_ms},
          {"densify", t.densify_ms},
          {"grouping", t.grouping_ms},
          {"roi_disparity", t.roi_disparity_ms},
          {"slic", t.slic_ms},
          {"planes", t.planes_ms},
          {"boundaries", t.boundaries_ms},
          {"regions", t.regions_ms},
          {"motion_carve", t.motion_carve_ms},
          {"band", t.band_ms},
          {"features", t.features_ms},
          {"total", t.total_ms}};
}

// Per ground-truth object of a frame (moving or not): its visible moving pixels, the tracked and dynamic points on
// it, how much of it the ROIs and the mask cover, and the IoU of the detection matched to it (0 = missed). This
// tells at which stage an object was lost (no dynamic points, no ROI, or a poor outline).
// gt_instances (may be empty): each pixel's object id; with it, an object's pixels are its own ones only.
// gt_disparity_px (may be empty, the simulator's disp_0/): with it, each object's distance (bf over the median
// ground-truth disparity of its own pixels).
nlohmann::json object_diagnostics(const std::vector<agvslam::io::SceneObject>* objects, const cv::Mat& gt_mask,
                                  const cv::Mat& gt_instances, const cv::Mat& gt_disparity_px, double bf_px_m,
                                  const dyn::DetectorResult& r, const eval::FrameDetectionScore& f) {
  nlohmann::json out = nlohmann::json::array();
  if (objects == nullptr) return out;
  const cv::Rect frame_rect(cv::Point(0, 0), gt_mask.size());
  for (const auto& obj : *objects) {
    const cv::Rect box = obj.box & frame_rect;
    int pixels = 0, in_mask = 0, in_roi = 0, tracked = 0, dynamic = 0;
    auto own = [&](int x, int y) { return gt_instances.empty() || gt_instances.at<uint8_t>(y, x) == obj.id; };
    std::vector<float> disparities;
    for (int y = box.y; y < box.br().y; ++y) {
      const uint8_t* g = gt_mask.ptr<uint8_t>(y);
      const uint8_t* d = r.mask.image.ptr<uint8_t>(y);
      const float* gd = gt_disparity_px.empty() ? nullptr : gt_disparity_px.ptr<float>(y);
      for (int x = box.x; x < box.br().x; ++x) {
        if (!g[x] || !own(x, y)) continue;
        ++pixels;
        if (gd != nullptr && gd[x] > 0) disparities.push_back(gd[x]);
        in_mask += d[x] ? 1 : 0;
        for (const auto& roi : r.rois) {
          if (roi.roi.contains(cv::Point(x, y))) {
            ++in_roi;
            break;
          }
        }
      }
    }
    for (const auto& p : r.points) {
      if (!p.tracked) continue;
      const cv::Point q(cvRound(p.cur_px.x), cvRound(p.cur_px.y));
      if (!box.contains(q) || (obj.moving && !gt_mask.at<uint8_t>(q)) || !own(q.x, q.y)) continue;
      ++tracked;
      dynamic += p.dynamic ? 1 : 0;
    }
    double iou = 0;
    for (const auto& d : f.detections) {
      if (d.matched_object_id == obj.id) iou = d.iou;
    }
    double distance_m = -1;  // unknown
    if (!disparities.empty() && bf_px_m > 0)
      distance_m = bf_px_m / static_cast<double>(dyn::median_in_place(disparities, 0.0f));
    out.push_back({{"id", obj.id},
                   {"class", obj.object_class},
                   {"moving", obj.moving},
                   {"pixels", pixels},
                   {"in_mask", in_mask},
                   {"in_roi", in_roi},
                   {"tracked_points", tracked},
                   {"dynamic_points", dynamic},
                   {"iou", iou},
                   {"distance_m", distance_m}});
  }
  return out;
}

// Recall by the objects' visible size, by whether the image border cuts them (the detector's hard cases: far
// people, people entering or leaving the view) and, where the dataset has ground-truth disparity, by distance,
// from the per-object diagnostics.
struct RecallBreakdown {
  static constexpr int kBins = 4;
  static constexpr int kUpper[kBins - 1] = {1500, 5000, 20000};  // visible moving pixels
  static constexpr int kDistanceBins = 4;
  static constexpr double kDistanceUpperM[kDistanceBins - 1] = {4.0, 7.0, 12.0};
  int found[kBins] = {}, total[kBins] = {};
  int distance_found[kDistanceBins] = {}, distance_total[kDistanceBins] = {};
  int border_found = 0, border_total = 0, inner_found = 0, inner_total = 0;
  // Objects within 4 m in full view: not cut by the border, and no nearer moving object's box over theirs (a person
  // the vehicle must not lose, seen whole; objects that do not move have no ground-truth distance here).
  int full_view_found = 0, full_view_total = 0;
  int left_found = 0, left_total = 0, right_found = 0, right_total = 0;  // cut by the left / the right border
  // By the detector's tracked points on the object's own pixels (0 / 1-2 / 3-4 / 5-9 / >= 10): a detector built on
  // sparse tracks (paper 004) cannot find an object without them, so the first bins bound what it can reach.
  static constexpr int kTrackBins = 5;
  static constexpr int kTrackUpper[kTrackBins - 1] = {1, 3, 5, 10};
  static constexpr const char* kTrackBinNames[kTrackBins] = {"0", "1_2", "3_4", "5_9", "ge10"};
  int track_found[kTrackBins] = {}, track_total[kTrackBins] = {};
  // Where each missed object was lost, by distance (< 4 m, 4-12 m, >= 12 m, unknown): no tracked point on it; tracked
  // points but none dynamic; dynamic points but no ROI over it; ROIs over it (its own, rejected or withheld, or another
  // object's) but none of its pixels in the mask; or masked, with the matching IoU below the scoring's.
  static constexpr int kMissBands = 4;
  static constexpr int kMissStages = 5;
  static constexpr const char* kMissBandNames[kMissBands] = {"lt4m", "4_12m", "ge12m", "unknown"};
  static constexpr const char* kMissStageNames[kMissStages] = {"no_track", "no_dynamic_point", "no_roi",
                                                               "roi_not_masked", "outline_below_iou"};
  int misses[kMissBands][kMissStages] = {};
  // By the object's ground-truth image motion against a static object's (eval/object_motion.h, frame to frame;
  // "visible part changed": entering, leaving or passing behind something), per distance band as the misses.
  static constexpr int kMotionBins = 5;
  static constexpr double kMotionUpperPx[kMotionBins - 2] = {1.0, 2.0, 4.0};
  int motion_found[kMissBands][kMotionBins] = {}, motion_total[kMissBands][kMotionBins] = {};
  static constexpr double kNearM = 4.0;
  static constexpr double kFarM = 12.0;
  static constexpr int kBorderPx = 2;  // a box within this of the left/right edge is cut by it

  void add(const std::vector<agvslam::io::SceneObject>& objects, const nlohmann::json& diagnostics, cv::Size size,
           const eval::DetectionScoringConfig& scoring) {
    for (const auto& d : diagnostics) {
      if (!d["moving"].get<bool>() || d["pixels"].get<int>() < std::max(1, scoring.min_object_pixels)) continue;
      const int id = d["id"].get<int>();
      const auto obj = std::find_if(objects.begin(), objects.end(), [&](const auto& o) { return o.id == id; });
      if (obj == objects.end()) continue;
      const bool hit = d["iou"].get<double>() >= scoring.min_iou;
      int bin = 0;
      while (bin < kBins - 1 && d["pixels"].get<int>() >= kUpper[bin]) ++bin;
      ++total[bin];
      found[bin] += hit;
      const bool cut_left = obj->box.x <= kBorderPx, cut_right = obj->box.br().x >= size.width - kBorderPx;
      const bool cut = cut_left || cut_right;
      (cut ? border_total : inner_total) += 1;
      (cut ? border_found : inner_found) += hit;
      left_total += cut_left;
      left_found += cut_left && hit;
      right_total += cut_right;
      right_found += cut_right && hit;
      int track_bin = 0;
      while (track_bin < kTrackBins - 1 && d["tracked_points"].get<int>() >= kTrackUpper[track_bin]) ++track_bin;
      ++track_total[track_bin];
      track_found[track_bin] += hit;
      const double distance_m = d.value("distance_m", -1.0);
      const int band = !(distance_m > 0) ? 3 : distance_m < kNearM ? 0 : distance_m < kFarM ? 1 : 2;
      if (d.contains("gt_motion_px")) {
        int k = kMotionBins - 1;  // visible part changed
        if (d["gt_motion_valid"].get<bool>()) {
          const double motion_px = d["gt_motion_px"].get<double>();
          k = 0;
          while (k < kMotionBins - 2 && motion_px >= kMotionUpperPx[k]) ++k;
        }
        ++motion_total[band][k];
        motion_found[band][k] += hit;
      }
      if (!hit) {
        const int stage = d["in_mask"].get<int>() > 0          ? 4
                          : d["in_roi"].get<int>() > 0         ? 3
                          : d["dynamic_points"].get<int>() > 0 ? 2
                          : d["tracked_points"].get<int>() > 0 ? 1
                                                               : 0;
        ++misses[band][stage];
      }
      if (distance_m > 0) {
        int k = 0;
        while (k < kDistanceBins - 1 && distance_m >= kDistanceUpperM[k]) ++k;
        ++distance_total[k];
        distance_found[k] += hit;
      }
      if (distance_m > 0 && distance_m < kNearM && !cut) {
        bool covered = false;
        for (const auto& other : diagnostics) {
          const double other_m = other.value("distance_m", -1.0);
          if (other["id"].get<int>() == id || !(other_m > 0) || other_m >= distance_m) continue;
          const auto o2 = std::find_if(objects.begin(), objects.end(),
                                       [&](const auto& o) { return o.id == other["id"].get<int>(); });
          covered = covered || (o2 != objects.end() && (o2->box & obj->box).area() > 0);
        }
        if (!covered) {
          ++full_view_total;
          full_view_found += hit;
        }
      }
    }
  }
  static std::string ratio(int f, int t) {
    if (t == 0) return "- (0/0)";
    char buf[48];
    std::snprintf(buf, sizeof(buf), "%.3f (%d/%d)", static_cast<double>(f) / t, f, t);
    return buf;
  }
  // "<title> <band> c0 / c1 / ...; <band> ..." over the distance bands with objects; cell(b, k) formats one entry.
  template <typename Cell>
  static std::string per_band(std::string text, int columns, const std::array<int, kMissBands>& totals, Cell cell) {
    const char* labels[kMissBands] = {"< 4 m", "4-12 m", ">= 12 m", "distance unknown"};
    for (int b = 0; b < kMissBands; ++b) {
      if (totals[static_cast<std::size_t>(b)] == 0) continue;
      text += std::string(" ") + labels[b] + " " + cell(b, 0);
      for (int k = 1; k < columns; ++k) text += " / " + cell(b, k);
      text += ";";
    }
    if (text.back() == ';') text.pop_back();
    return text;
  }
  // Per distance band, the sum over its columns.
  template <int Columns>
  static std::array<int, kMissBands> band_totals(const int (&counts)[kMissBands][Columns]) {
    std::array<int, kMissBands> totals{};
    for (int b = 0; b < kMissBands; ++b)
      for (int k = 0; k < Columns; ++k) totals[static_cast<std::size_t>(b)] += counts[b][k];
    return totals;
  }
  std::string describe_misses() const {
    return per_band(
        "misses by where they were lost (no track / no dynamic point / no ROI / ROI, not in the mask / "
        "outline IoU too low):",
        kMissStages, band_totals(misses), [&](int b, int k) { return std::to_string(misses[b][k]); });
  }
  bool has_motion() const {
    const std::array<int, kMissBands> totals = band_totals(motion_total);
    return std::any_of(totals.begin(), totals.end(), [](int n) { return n > 0; });
  }
  std::string describe_motion() const {
    return per_band(
        "recall by ground-truth image motion against a static object's, frame to frame (< 1 / 1-2 / 2-4 / "
        ">= 4 px / visible part changed):",
        kMotionBins, band_totals(motion_total),
        [&](int b, int k) { return ratio(motion_found[b][k], motion_total[b][k]); });
  }
  nlohmann::json motion_json() const {
    const char* names[kMotionBins] = {"lt1px", "1_2px", "2_4px", "ge4px", "visible_part_changed"};
    nlohmann::json j;
    for (int b = 0; b < kMissBands; ++b) {
      for (int k = 0; k < kMotionBins; ++k) {
        j[kMissBandNames[b]][names[k]] = {{"found", motion_found[b][k]}, {"objects", motion_total[b][k]}};
      }
    }
    return j;
  }
  nlohmann::json misses_json() const {
    nlohmann::json j;
    for (int b = 0; b < kMissBands; ++b) {
      for (int k = 0; k < kMissStages; ++k) j[kMissBandNames[b]][kMissStageNames[k]] = misses[b][k];
    }
    return j;
  }
  std::string describe() const {
    return "recall by visible size: <1500 px " + ratio(found[0], total[0]) + ", 1500-5000 px " +
           ratio(found[1], total[1]) + ", 5000-20000 px " + ratio(found[2], total[2]) + ", >= 20000 px " +
           ratio(found[3], total[3]) + "; cut by the left/right image border " + ratio(border_found, border_total) +
           " (left " + ratio(left_found, left_total) + ", right " + ratio(right_found, right_total) +
           "), inside the image " + ratio(inner_found, inner_total) + "; by tracked points on the object: 0 " +
           ratio(track_found[0], track_total[0]) + ", 1-2 " + ratio(track_found[1], track_total[1]) + ", 3-4 " +
           ratio(track_found[2], track_total[2]) + ", 5-9 " + ratio(track_found[3], track_total[3]) + ", >= 10 " +
           ratio(track_found[4], track_total[4]) +
           (distance_total[0] + distance_total[1] + distance_total[2] + distance_total[3] == 0
                ? std::string()
                : "; by distance: < 4 m " + ratio(distance_found[0], distance_total[0]) + ", 4-7 m " +
                      ratio(distance_found[1], distance_total[1]) + ", 7-12 m " +
                      ratio(distance_found[2], distance_total[2]) + ", >= 12 m " +
                      ratio(distance_found[3], distance_total[3]) + "; within 4 m in full view (not cut, " +
                      "no nearer mover over it) " + ratio(full_view_found, full_view_total));
  }
  nlohmann::json to_json() const {
    nlohmann::json j;
    const char* names[kBins] = {"lt1500", "1500_5000", "5000_20000", "ge20000"};
    for (int b = 0; b < kBins; ++b) j["size_" + std::string(names[b])] = {{"found", found[b]}, {"objects", total[b]}};
    j["border"] = {{"found", border_found}, {"objects", border_total}};
    j["border_left"] = {{"found", left_found}, {"objects", left_total}};
    j["border_right"] = {{"found", right_found}, {"objects", right_total}};
    j["inside"] = {{"found", inner_found}, {"objects", inner_total}};
    j["full_view_lt4m"] = {{"found", full_view_found}, {"objects", full_view_total}};
    for (int b = 0; b < kTrackBins; ++b) {
      j["tracks_" + std::string(kTrackBinNames[b])] = {{"found", track_found[b]}, {"objects", track_total[b]}};
    }
    const char* distance_names[kDistanceBins] = {"lt4m", "4_7m", "7_12m", "ge12m"};
    for (int b = 0; b < kDistanceBins; ++b) {
      j["distance_" + std::string(distance_names[b])] = {{"found", distance_found[b]}, {"objects", distance_total[b]}};
    }
    return j;
  }
};

// Per detected object: its box and size, the object it matched (-1 none) and how many of its pixels lie on
// moving ground truth (a false positive on a moving object is a split or merged outline, elsewhere a false alarm).
nlohmann::json detection_diagnostics(const eval::FrameDetectionScore& f, const cv::Mat& instances,
                                     const cv::Mat& gt_mask) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& d : f.detections) {
    // Instances are numbered in the order score_detection_instances lists them (increasing label), so the
    // detection's label is the one most of its box's instance pixels carry.
    std::map<int, int> count;
    for (int y = d.box.y; y < d.box.br().y; ++y)
      for (int x = d.box.x; x < d.box.br().x; ++x)
        if (const int k = instances.at<uint8_t>(y, x)) ++count[k];
    int label = 0, best = -1;
    for (const auto& [k, c] : count) {
      if (c > best) {
        best = c;
        label = k;
      }
    }
    int on_moving = 0;
    for (int y = d.box.y; y < d.box.br().y; ++y)
      for (int x = d.box.x; x < d.box.br().x; ++x)
        on_moving += instances.at<uint8_t>(y, x) == label && gt_mask.at<uint8_t>(y, x) ? 1 : 0;
    out.push_back({{"box", {d.box.x, d.box.y, d.box.width, d.box.height}},
                   {"pixels", d.pixels},
                   {"matched", d.matched_object_id},
                   {"iou", d.iou},
                   {"ignored", d.ignored},
                   {"on_moving", on_moving}});
  }
  return out;
}

std::string fmt(double v, const char* format = "%.4f") {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

// The dataset's ground truth where it has one (the simulator: mask_0/, instance_0/, disp_0/, objects.txt,
// poses.txt).
struct GroundTruth {
  bool has_masks = false;
  std::map<int, std::vector<agvslam::io::SceneObject>> objects;  // by frame
  // Poses and the last frame's instances and disparity: each object's image motion against a static object's.
  std::optional<agvslam::Trajectory> poses;
  cv::Mat last_instances, last_disparity_px;
};

GroundTruth load_ground_truth(const agvslam::io::StereoDataset& dataset) {
  GroundTruth gt;
  gt.has_masks = fs::is_directory(fs::path(dataset.root()) / "mask_0");
  const fs::path objects_path = fs::path(dataset.root()) / "objects.txt";
  if (gt.has_masks && fs::exists(objects_path)) gt.objects = agvslam::io::read_objects_file(objects_path.string());
  if (gt.has_masks) gt.poses = dataset.ground_truth();
  return gt;
}

// One frame's ground truth (empty images where the dataset has none).
struct FrameTruth {
  cv::Mat mask, instances, disparity_px;
};

// Sums over the frames.
struct Totals {
  eval::DetectionScore score;
  std::map<std::string, Series> timings;  // per stage (ms)
  std::vector<std::string> stage_order;   // as the detector reports them
  int regions = 0, frames_detected = 0, frames_with_regions = 0, unconfirmed = 0;
  int instances_scored = 0;  // frames whose objects were scored with instance_0/ (their own pixels only)
  RecallBreakdown breakdown;
  nlohmann::json per_frame = nlohmann::json::array();

  void add_time(const std::string& stage, double ms) {
    if (timings.find(stage) == timings.end()) stage_order.push_back(stage);
    timings[stage].add(ms);
  }
};

// mask/, overlay/, rois/ and instances/ under --out.
void create_output_folders(const Options& o) {
  const fs::path out(o.out_dir);
  std::error_code ec;
  fs::create_directories(out / "mask", ec);
  if (ec) throw InputError("--out", o.out_dir, "a folder that can be created (" + ec.message() + ")");
  if (o.overlay_every > 0) fs::create_directories(out / "overlay", ec);
  if (o.dump_rois) {
    fs::create_directories(out / "rois", ec);
    fs::create_directories(out / "instances", ec);
  }
}

// The tracked points by test (and with --json-points each of them), and the multi-frame test's figures.
void add_points_json(const Options& o, const dyn::DetectorResult& result, const cv::Mat& gt_mask, nlohmann::json& jf) {
  int tracked = 0, epi = 0, depth = 0, multi = 0;
  for (const auto& p : result.points) {
    tracked += p.tracked ? 1 : 0;
    epi += p.dynamic_epipolar ? 1 : 0;
    depth += p.dynamic_depth ? 1 : 0;
    multi += p.dynamic_multiframe ? 1 : 0;
  }
  if (o.json_points) {
    nlohmann::json jp = nlohmann::json::array();
    for (const auto& p : result.points) {
      if (!p.tracked) continue;
      const cv::Point q(cvRound(p.cur_px.x), cvRound(p.cur_px.y));
      const int on_gt = gt_mask.empty() ? -1 : (gt_mask.at<uint8_t>(q) ? 1 : 0);
      jp.push_back({{"x", p.cur_px.x},
                    {"y", p.cur_px.y},
                    {"d", p.cur_disparity_px},
                    {"age", p.age},
                    {"densified", p.densified},
                    {"d_epi", p.d_epi_px},
                    {"t_epi", p.t_epi_px},
                    {"reproj", p.reprojection_px},
                    {"disp_res", p.disparity_residual_px},
                    {"mf", p.multiframe_px},
                    {"mf_disp", p.multiframe_disparity_residual_px},
                    {"epipolar", p.dynamic_epipolar},
                    {"depth", p.dynamic_depth},
                    {"multiframe", p.dynamic_multiframe},
                    {"dynamic", p.dynamic},
                    {"group", p.group},
                    {"on_gt", on_gt}});
    }
    jf["tracked_points"] = jp;
  }
  jf["points"] = {{"tracked", tracked}, {"epipolar", epi}, {"depth", depth}, {"multiframe", multi}};
  jf["multiframe"] = {{"valid", result.multiframe.valid},
                      {"frames_back", result.multiframe.frames_back},
                      {"translation_m", result.multiframe.translation_m},
                      {"candidates", result.multiframe.candidates},
                      {"flagged", result.multiframe.flagged},
                      {"confirmed", result.multiframe.confirmed},
                      {"a_reproj_px", result.multiframe.test.a_reproj_used_px},
                      {"a_disp_px", result.multiframe.test.a_disp_used_px}};
}

// Every ROI with an outline: its size, verdict, points and motion; with --dump-rois also its outline as a PNG
// (rois/<frame>_<k>.png, whatever its verdict) and its dynamic points' positions in both frames.
nlohmann::json rois_json(const Options& o, std::size_t frame, const dyn::DetectorResult& result,
                         const cv::Mat& gt_mask) {
  nlohmann::json jr = nlohmann::json::array();
  for (std::size_t k = 0; k < result.rois.size(); ++k) {
    const auto& roi = result.rois[k];
    if (roi.outline.empty()) continue;
    const int px = cv::countNonZero(roi.outline);
    const int on_gt = gt_mask.empty() ? -1 : cv::countNonZero(roi.outline & gt_mask(roi.roi));
    jr.push_back({{"roi", {roi.roi.x, roi.roi.y, roi.roi.width, roi.roi.height}},
                  {"pixels", px},
                  {"on_gt", on_gt},
                  {"points", roi.points.size()},
                  {"tracked_inside", roi.outline_stats.tracked_inside},
                  {"dynamic_inside", roi.outline_stats.dynamic_inside},
                  {"multiframe_tested_inside", roi.outline_stats.multiframe_tested_inside},
                  {"multiframe_dynamic_inside", roi.outline_stats.multiframe_dynamic_inside},
                  {"d", roi.mean_disparity_px},
                  {"motion", roi.outline_motion.apparent_motion_px},
                  {"motion_multiframe", roi.outline_motion_multiframe.apparent_motion_px},
                  {"verdict", dyn::to_string(roi.outline_verdict)},
                  {"coasted", roi.coasted},
                  {"median_offset", roi.outline_stats.median_offset_px},
                  {"object", roi.object_id},
                  {"motion_carve",
                   {{"ran", roi.motion_carve.ran},
                    {"blocks_tested", roi.motion_carve.blocks_tested},
                    {"blocks_static", roi.motion_carve.blocks_static},
                    {"pixels_removed", roi.motion_carve.pixels_removed}}}});
    if (o.dump_rois) {
      char name[48];
      std::snprintf(name, sizeof(name), "%06zu_%02zu.png", frame, k);
      write_png((fs::path(o.out_dir) / "rois" / name).string(), roi.outline);
      nlohmann::json tracks = nlohmann::json::array();
      for (int idx : roi.points) {
        const auto& p = result.points[static_cast<std::size_t>(idx)];
        tracks.push_back({p.prev_px.x, p.prev_px.y, p.cur_px.x, p.cur_px.y, p.cur_disparity_px});
      }
      jr.back()["outline_png"] = std::string("rois/") + name;
      jr.back()["tracks"] = tracks;
    }
  }
  return jr;
}

// The frame scored against the ground-truth masks (eqs. 12-14), with per-object and per-detection diagnostics and
// each moving object's ground-truth image motion since the last frame (eval/object_motion.h).
void score_frame(std::size_t i, std::size_t first, const agvslam::io::StereoDataset& dataset, const GroundTruth& gt,
                 const FrameTruth& truth, const eval::DetectionScoringConfig& scoring,
                 const dyn::DetectorResult& result, Totals& totals, nlohmann::json& jf) {
  std::vector<eval::GroundTruthObject> gt_objects;
  const auto it = gt.objects.find(static_cast<int>(i));
  if (it != gt.objects.end()) {
    for (const auto& obj : it->second) {
      if (obj.moving) gt_objects.push_back({obj.id, obj.box});
    }
  }
  const eval::FrameDetectionScore f =
      eval::score_detection_instances(result.mask.instances, truth.mask, gt_objects, scoring, truth.instances);
  totals.score.add(f);
  totals.instances_scored += truth.instances.empty() ? 0 : 1;
  jf["tp"] = f.true_positives;
  jf["fp"] = f.false_positives;
  jf["fn"] = f.false_negatives;
  jf["iou"] = f.matched_iou;
  jf["objects"] = object_diagnostics(it == gt.objects.end() ? nullptr : &it->second, truth.mask, truth.instances,
                                     truth.disparity_px, dataset.calibration().bf(), result, f);
  if (gt.poses && i < gt.poses->size() && i > first && !truth.instances.empty() && !truth.disparity_px.empty() &&
      !gt.last_instances.empty() && !gt.last_disparity_px.empty()) {
    const agvslam::SE3d T_now_then = (*gt.poses)[i].T_w_c.inverse() * (*gt.poses)[i - 1].T_w_c;
    for (auto& d : jf["objects"]) {
      if (!d["moving"].get<bool>()) continue;
      const eval::ObjectImageMotion m = eval::ground_truth_image_motion(
          gt.last_instances, gt.last_disparity_px, truth.instances, truth.disparity_px, d["id"].get<int>(),
          dataset.calibration().left, dataset.calibration().bf(), T_now_then);
      d["gt_motion_px"] = m.offset_px;
      d["gt_motion_valid"] = m.valid;
    }
  }
  if (it != gt.objects.end()) totals.breakdown.add(it->second, jf["objects"], truth.mask.size(), scoring);
  jf["detections"] = detection_diagnostics(f, result.mask.instances, truth.mask);
}

// The figures of a frame the detector compared with a previous one: stage times, regions, band, points, ROIs and,
// with ground truth, the scores.
void add_detected_frame(const Options& o, std::size_t i, std::size_t first, const agvslam::io::StereoDataset& dataset,
                        const GroundTruth& gt, const FrameTruth& truth, const eval::DetectionScoringConfig& scoring,
                        const dyn::DetectorResult& result, double detect_cpu_ms, Totals& totals, nlohmann::json& jf) {
  ++totals.frames_detected;
  for (const auto& [name, ms] : stage_values(result.timings)) totals.add_time(name, ms);
  // The detector's CPU time on this thread (all of it with --opencv-threads 1): robust to other load.
  totals.add_time("total_cpu", detect_cpu_ms);
  const int n_regions = static_cast<int>(result.mask.regions.size());
  totals.regions += n_regions;
  totals.frames_with_regions += n_regions > 0 ? 1 : 0;
  jf["regions"] = n_regions;
  if (result.band.ran) {
    jf["band"] = {{"static_segment_px", result.band.static_segment_px},
                  {"tracks", result.band.tracks},
                  {"corners", result.band.corners},
                  {"seeds", result.band.seeds.size()},
                  {"regions", result.band.regions.size()},
                  {"joined", result.band_joined},
                  {"objects", result.band_objects},
                  {"ms", result.timings.band_ms}};
  }
  if (result.band_driving_seeds > 0) {
    jf["band_driving"] = {{"seeds", result.band_driving_seeds}, {"dynamic", result.band_driving_dynamic}};
  }
  jf["unconfirmed_objects"] = result.unconfirmed_objects;  // found, not reported (confirm.min_box_iou)
  totals.unconfirmed += result.unconfirmed_objects;
  jf["dynamic_points"] = result.dynamic_point_count();
  add_points_json(o, result, truth.mask, jf);
  jf["mask_pixels"] = result.mask.pixel_count();
  jf["total_ms"] = result.timings.total_ms;
  jf["lk_levels"] = result.lk_levels;
  if (result.ground_plane.valid) {
    jf["ground_plane"] = {result.ground_plane.a, result.ground_plane.b, result.ground_plane.c};
  }
  jf["rois"] = rois_json(o, i, result, truth.mask);
  if (!truth.mask.empty()) score_frame(i, first, dataset, gt, truth, scoring, result, totals, jf);
}

// PRECISION line, counts, scores with their breakdowns and the stage times.
void print_summary(bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals) {
  const double nan = std::nan("");
  const eval::DetectionScore& score = totals.score;
  const double p = scored ? score.precision() : nan, r = scored ? score.recall() : nan,
               iou = scored ? score.mean_iou() : nan;
  std::printf("PRECISION %s RECALL %s IOU %s\n", fmt(p).c_str(), fmt(r).c_str(), fmt(iou).c_str());
  std::printf(
      "frames: %d detected (the first has no previous frame); %d regions, %.3f per frame, %d frames with regions\n",
      totals.frames_detected, totals.regions,
      totals.frames_detected > 0 ? static_cast<double>(totals.regions) / totals.frames_detected : 0.0,
      totals.frames_with_regions);
  if (scored) {
    std::printf(
        "objects (IoU >= %.2f, objects under %d px don't care; %s): TP %d FP %d FN %d, %d don't-care; "
        "false regions per 100 frames %.2f\n",
        scoring.min_iou, scoring.min_object_pixels,
        totals.instances_scored == score.frames() ? "each object its own pixels (instance_0/)"
        : totals.instances_scored == 0            ? "each object the moving pixels in its box (no instance_0/)"
                                                  : "instance_0/ for some frames only",
        score.true_positives(), score.false_positives(), score.false_negatives(), score.ignored_objects(),
        score.false_positives_per_100_frames());
    std::printf("pixels: precision %.4f recall %.4f IoU %.4f\n", score.pixel_precision(), score.pixel_recall(),
                score.pixel_iou());
    std::printf("%s\n", totals.breakdown.describe().c_str());
    std::printf("%s\n", totals.breakdown.describe_misses().c_str());
    if (totals.breakdown.has_motion()) std::printf("%s\n", totals.breakdown.describe_motion().c_str());
  } else {
    std::printf("no ground-truth masks (mask_0/) in the dataset: not scored\n");
  }
  std::printf("time per frame [ms]      median      p95\n");
  for (const auto& name : totals.stage_order) {
    std::printf("  %-20s %9.3f %8.3f\n", name.c_str(), totals.timings[name].median(),
                totals.timings[name].quantile(0.95));
  }
}

void write_json(const Options& o, const agvslam::io::StereoDataset& dataset, std::size_t first, std::size_t last,
                bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals) {
  const eval::DetectionScore& score = totals.score;
  nlohmann::json j;
  j["dataset"] = dataset.root();
  j["frames"] = {{"first", first}, {"last", last}, {"detected", totals.frames_detected}};
  j["regions"] = {
      {"total", totals.regions},
      {"per_frame", totals.frames_detected > 0 ? static_cast<double>(totals.regions) / totals.frames_detected : 0.0},
      {"unconfirmed_objects", totals.unconfirmed}};
  if (scored) {
    j["scoring"] = {{"min_iou", scoring.min_iou},
                    {"min_object_pixels", scoring.min_object_pixels},
                    {"instance_frames", totals.instances_scored}};
    j["precision"] = score.precision();
    j["recall"] = score.recall();
    j["mean_iou"] = score.mean_iou();
    j["true_positives"] = score.true_positives();
    j["false_positives"] = score.false_positives();
    j["false_negatives"] = score.false_negatives();
    j["dont_care_objects"] = score.ignored_objects();
    j["false_regions_per_100_frames"] = score.false_positives_per_100_frames();
    j["pixel"] = {{"precision", score.pixel_precision()}, {"recall", score.pixel_recall()}, {"iou", score.pixel_iou()}};
    j["recall_breakdown"] = totals.breakdown.to_json();
    j["misses_by_stage"] = totals.breakdown.misses_json();
    if (totals.breakdown.has_motion()) j["recall_by_ground_truth_motion"] = totals.breakdown.motion_json();
  }
  nlohmann::json jt;
  for (const auto& name : totals.stage_order) {
    jt[name] = {{"median_ms", totals.timings[name].median()}, {"p95_ms", totals.timings[name].quantile(0.95)}};
  }
  j["timings"] = jt;
  j["per_frame"] = totals.per_frame;
  std::string text = j.dump(2) + "\n";
  agvslam::io::write_file_atomically(o.json_path, text);
}

// The semantic stage of --semantic MODEL, or null (off, or a model that cannot be loaded: geometry alone).
std::unique_ptr<agvslam::semantic::SemanticMasker> open_semantic(const Options& o) {
  namespace sem = agvslam::semantic;
  if (o.semantic == "off") return nullptr;
  sem::SemanticConfig config =
      o.params_semantic.empty() ? sem::SemanticConfig{} : sem::load_semantic_config(o.params_semantic);
  config.model.path = o.semantic;
  config.fusion.synchronous = true;
  std::unique_ptr<sem::Segmenter> segmenter;
  try {
    segmenter = std::make_unique<sem::Segmenter>(config.model);
  } catch (const InputError& e) {
    spdlog::warn("--semantic: {}; continuing with the geometric detector alone", e.what());
    return nullptr;
  }
  spdlog::info("  semantic settings{}",
               o.params_semantic.empty() ? " (built-in defaults)" : " from " + o.params_semantic);
  for (const auto& line : config.describe()) spdlog::info("    {}", line);
  return std::make_unique<sem::SemanticMasker>(config, std::move(segmenter));
}

int run(const Options& o) {
  const auto dataset = agvslam::io::open_dataset(o.dataset, o.calib);
  std::size_t first = 0, last = 0;
  agvslam::io::parse_frame_range(o.frames, dataset->size(), "--frames", o.frames, first, last);

  const dyn::DynamicDetectorConfig dynamic_config =
      o.params_dynamic.empty() ? dyn::DynamicDetectorConfig{} : dyn::load_dynamic_config(o.params_dynamic);
  const agvslam::stereo::StereoConfig stereo_config =
      o.params_stereo.empty() ? agvslam::stereo::StereoConfig{} : agvslam::stereo::load_stereo_config(o.params_stereo);
  spdlog::info("agvslam-dynamic: {} dataset {} ({} frames, using {}..{})", dataset->kind(), dataset->root(),
               dataset->size(), first, last);
  spdlog::info("  calibration: {}", dataset->calibration().summary());
  spdlog::info("  detector settings{}",
               o.params_dynamic.empty() ? " (built-in defaults)" : " from " + o.params_dynamic);
  for (const auto& line : dynamic_config.describe()) spdlog::info("    {}", line);
  spdlog::info("  stereo settings{}", o.params_stereo.empty() ? " (built-in defaults)" : " from " + o.params_stereo);
  for (const auto& line : stereo_config.describe()) spdlog::info("    {}", line);

  GroundTruth gt = load_ground_truth(*dataset);
  eval::DetectionScoringConfig scoring;
  scoring.min_iou = o.min_iou;
  scoring.min_object_pixels = o.min_object_pixels;
  create_output_folders(o);
  const fs::path out(o.out_dir);

  cv::setNumThreads(o.opencv_threads);
  dyn::DynamicDetector detector(dataset->calibration(), dynamic_config, stereo_config);
  const std::unique_ptr<agvslam::semantic::SemanticMasker> semantic = open_semantic(o);
  agvslam::stereo::StereoSgbm display_sgbm(stereo_config.sgbm);
  dyn::DetectorResult result;
  Totals totals;
  int previous_dynamic_points = -1;
  for (std::size_t i = first; i <= last; ++i) {
    const agvslam::StereoFrame frame = dataset->frame(i);
    const double cpu_before_ms = thread_cpu_ms();
    detector.detect(frame, result);
    const double detect_cpu_ms = thread_cpu_ms() - cpu_before_ms;
    if (semantic) {
      agvslam::semantic::FrameCues cues;
      cues.previous_dynamic_points = previous_dynamic_points;
      semantic->process(i, frame.left, &result, cues);
      semantic->apply_fusion(result.mask);  // scored, written and drawn as the detector's own mask
    }
    previous_dynamic_points = result.dynamic_point_count();
    write_png((out / "mask" / frame_name(i)).string(), result.mask.image);
    if (o.dump_rois) write_png((out / "instances" / frame_name(i)).string(), result.mask.instances);
    FrameTruth truth;
    if (gt.has_masks) {
      truth.mask = dataset->ground_truth_mask(i);
      truth.instances = dataset->ground_truth_instances(i);        // empty without instance_0/
      truth.disparity_px = dataset->ground_truth_disparity_px(i);  // empty without disp_0/
    }
    nlohmann::json jf;
    jf["frame"] = i;
    if (result.has_previous)
      add_detected_frame(o, i, first, *dataset, gt, truth, scoring, result, detect_cpu_ms, totals, jf);
    totals.per_frame.push_back(jf);
    gt.last_instances = truth.instances;
    gt.last_disparity_px = truth.disparity_px;
    if (o.overlay_every > 0 && result.has_previous && (i - first) % static_cast<std::size_t>(o.overlay_every) == 0) {
      write_png((out / "overlay" / frame_name(i)).string(),
                compose_overlay(frame.left, frame.right, result, truth.mask, display_sgbm));
    }
    if ((i - first + 1) % 100 == 0) spdlog::info("  frame {}/{}", i - first + 1, last - first + 1);
  }

  if (semantic) {
    const agvslam::semantic::SemanticStats st = semantic->stats();
    spdlog::info(
        "semantic: {} frames sent to the network, {} segmented ({:.1f} ms each), {} carried late, {} dropped stale",
        st.requests, st.segmented, st.segmented ? st.segment_ms_total / static_cast<double>(st.segmented) : 0.0,
        st.late_results, st.stale_results);
  }
  const bool scored = gt.has_masks && totals.score.frames() > 0;
  print_summary(scored, scoring, totals);
  if (!o.json_path.empty()) write_json(o, *dataset, first, last, scored, scoring, totals);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the PRECISION line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-dynamic"));
  CLI::App app{
      "agvslam-dynamic: dynamic-region detection (paper 004) over a stereo sequence, scored where the "
      "dataset has ground-truth masks"};
  Options o;
  app.add_option("--dataset", o.dataset, "sequence folder (KITTI layout as agvslam-sim writes it, or EuRoC)")
      ->required();
  app.add_option("--out", o.out_dir, "output folder: mask/ and overlay/")->required();
  app.add_option("--json", o.json_path, "write the scores, per-stage timings and per-frame figures as JSON");
  app.add_option("--frames", o.frames, "inclusive frame range A:B (default: all)");
  app.add_option("--params-dynamic", o.params_dynamic, "detector settings (params/dynamic.yaml; default: built-in)");
  app.add_option("--params-stereo", o.params_stereo, "stereo settings (params/stereo.yaml; default: built-in)");
  app.add_option("--calib", o.calib, "calibration file overriding the dataset's");
  app.add_option("--semantic", o.semantic,
                 "segmentation model (ONNX) whose moving objects join the detector's mask, or off (default)");
  app.add_option("--params-semantic", o.params_semantic, "params/semantic.yaml (with --semantic MODEL)");
  app.add_flag(
      "--dump-rois", o.dump_rois,
      "debugging: write every ROI's outline (kept or dropped) to rois/, the reported objects to instances/ (8-bit ids) "
      "and the ROIs' dynamic points to the --json output");
  app.add_flag("--json-points", o.json_points,
               "add every tracked point (position, disparity, age, tests, residuals) "
               "of every frame to the --json output (large)");
  app.add_option("--opencv-threads", o.opencv_threads,
                 "OpenCV worker threads (1: the detector on one core, as its timings are specified)")
      ->check(CLI::PositiveNumber);
  app.add_option("--overlay-every", o.overlay_every, "write an overlay every N frames (0 = none)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-object-pixels", o.min_object_pixels,
                 "ground-truth objects with fewer visible moving pixels are don't-care")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-iou", o.min_iou, "IoU for a detection to match an object (paper: 0.5)")
      ->check(CLI::Range(0.01, 1.0));
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
