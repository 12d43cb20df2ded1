#pragma once
// Dynamic regions of interest (paper 004, III.A, eq. 4): two dynamic points belong to the same object when
//   |p_i - p_j| <= T_s = a_s + b_s * d   and   |d_i - d_j| <= T_disp,
// groups are the connected components of that relation (union-find), and a group of more than four points
// (min_points = 5) is a dynamic ROI: its bounding rectangle plus a margin that grows with the disparity
// (nearer objects are larger, and their outline lies further from the outermost corners). Optionally, groups
// whose ROIs overlap at agreeing disparity are merged (merge_overlapping).
// d in T_s is the mean of the two disparities (the relation must be symmetric); T_disp may grow with the
// disparity (t_disp_rel, 0 = the paper's constant) because the disparity spread of an object of fixed depth
// extent grows as d^2.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `grouping`.
struct RoiGroupingConfig {
  double a_s_px = 40.0;     // eq. 4 constant (px)
  double b_s = 1.5;         // eq. 4 slope (px per px of disparity)
  double t_disp_px = 3.0;   // T_disp constant (px)
  double t_disp_rel = 0.1;  // ... + t_disp_rel * d (0 = the paper's constant threshold)
  int min_points = 5;       // "more than four dynamic features"
  int margin_px = 16;       // ROI = bounding box + margin_px + margin_disparity_factor * d
  double margin_disparity_factor = 0.5;
  // Beyond the paper: groups (of >= 2 points) whose ROIs overlap, or are stacked vertically (overlapping
  // columns, vertical gap <= T_s), and whose mean disparities agree within T_disp are one object (a person's
  // torso and feet, with no corners on the thighs, are farther apart than T_s). Side-by-side groups (people
  // walking abreast) stay apart unless their ROIs overlap.
  // Merging happens before the min_points test, so two small groups of one object can make a ROI together.
  bool merge_overlapping = true;
  // Beyond the paper, with merge_overlapping: groups side by side at agreeing disparity, their rows overlapping
  // and their ROIs at most merge_side_gap_m apart (at their depth) are merged too: the two legs and the arm of a
  // striding person in textureless clothes, torso between them without corners. People walking abreast then share
  // a ROI; the disparity outline still separates them (detector.split_side_by_side). 0 = off.
  double merge_side_gap_m = 0.45;

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct DynamicGroup {
  std::vector<int> members;  // indices into the points given to group_dynamic_points
  cv::Rect bounds;           // bounding box of the members (px, inclusive of the points)
  cv::Rect roi;              // bounds + margin, clipped to the image
  double mean_disparity_px = 0;
};

// points_px/disparity_px: the dynamic points (disparity <= 0: unknown, such points are not grouped).
// baseline_m: the stereo baseline, for merge_side_gap_m (0: side-by-side groups are not merged).
// Returns the groups with at least min_points members, largest first.
std::vector<DynamicGroup> group_dynamic_points(const std::vector<cv::Point2f>& points_px,
                                               const std::vector<float>& disparity_px, cv::Size image_size,
                                               const RoiGroupingConfig& config, double baseline_m = 0.0);

}  // namespace agvslam::dynamic
