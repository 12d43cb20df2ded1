#pragma once
// agvslam-dynamic's report: each frame's figures (stage times, regions, points, ROIs and, where the dataset has ground
// truth, the scores with per-object and per-detection diagnostics) gathered as JSON, their sums over the frames, the
// summary on stdout and the --json file.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/stats.h"
#include "agvslam/core/trajectory.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/eval/detection_scoring.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/objects_io.h"
#include "dynamic_options.h"

namespace agvslam::apps::dynamic_tool {

namespace dyn = agvslam::dynamic;
namespace eval = agvslam::eval;

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

// The dataset's ground truth where it has one (the simulator: mask_0/, instance_0/, disp_0/, objects.txt,
// poses.txt).
struct GroundTruth {
  bool has_masks = false;
  std::map<int, std::vector<agvslam::io::SceneObject>> objects;  // by frame
  // Poses and the last frame's instances and disparity: each object's image motion against a static object's.
  std::optional<agvslam::Trajectory> poses;
  cv::Mat last_instances, last_disparity_px;
};

GroundTruth load_ground_truth(const agvslam::io::StereoDataset& dataset);

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
  // Pixels of people and vehicles standing still (instance_0/ and objects.txt), and of those the ones masked: the
  // features a detector must leave to the SLAM.
  int64_t still_pixels = 0, still_masked = 0;
  nlohmann::json per_frame = nlohmann::json::array();

  void add_time(const std::string& stage, double ms) {
    if (timings.find(stage) == timings.end()) stage_order.push_back(stage);
    timings[stage].add(ms);
  }
};

// The figures of a frame the detector compared with a previous one: stage times, regions, band, points, ROIs and,
// with ground truth, the scores.
void add_detected_frame(const Options& o, std::size_t i, std::size_t first, const agvslam::io::StereoDataset& dataset,
                        const GroundTruth& gt, const FrameTruth& truth, const eval::DetectionScoringConfig& scoring,
                        const dyn::DetectorResult& result, double detect_cpu_ms, Totals& totals, nlohmann::json& jf);

// PRECISION line, counts, scores with their breakdowns and the stage times.
void print_summary(bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals);

// The scores, per-stage times and per-frame figures to --json.
void write_json(const Options& o, const agvslam::io::StereoDataset& dataset, std::size_t first, std::size_t last,
                bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals);

}  // namespace agvslam::apps::dynamic_tool
