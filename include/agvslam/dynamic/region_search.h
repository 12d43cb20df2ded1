#pragma once
// Dynamic regions from dynamic points and boundary types (paper 004, III.B, last paragraph): from each
// dynamic point, search along +x, -x, +y and -y through the superpixel label image and stop at the first
// occlusion-type boundary (or the ROI edge); the minimum rectangle enclosing the found boundary points is
// the dynamic region. Also the tighter outline: the superpixels reached from the points' superpixels
// without crossing an occlusion boundary (a flood over coplanar and hinge boundaries), kept inside the
// rectangle.
// A point starts a search only from a superpixel whose plane agrees with the point's disparity (within
// start_radius_px of the point, the best-agreeing one): FAST corners often sit on an object's outline, where
// the pixel's own superpixel may belong to the background.
//
// Disparity band (beyond the paper, regions.disparity_band): the object's disparities are known from its
// dynamic points, so the search also stops on entering a superpixel whose plane lies outside the band
// [min d - tol, max d + tol] of the group, and superpixels without a plane (no SGBM disparity: textureless,
// or the half-occluded strip beside a foreground object) are crossed but do not extend the region. This
// makes the outline robust to a missed occlusion boundary (a superpixel straddling the object edge) and to
// the half-occluded background, which has no disparity at all.

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/dynamic/boundary.h"
#include "agvslam/dynamic/disparity_plane.h"

namespace agvslam::dynamic {

// kRectangle: the paper's rectangle; kSuperpixels: the flooded superpixels inside it; kDisparity: the object's
// pixels in the ROI's disparity (object_outline.h; SLIC, planes and boundaries are then not computed).
enum class MaskMode { kRectangle, kSuperpixels, kDisparity };
std::string to_string(MaskMode mode);
bool parse_mask_mode(const std::string& text, MaskMode& mode);

// params/dynamic.yaml, section `regions`.
struct RegionSearchConfig {
  int start_radius_px = 3;           // superpixels within this distance of a point are start candidates
  double start_tolerance_px = 1.5;   // |d_point - plane| allowed for a start superpixel ...
  double start_tolerance_rel = 0.1;  // ... + this fraction of d_point
  bool stop_at_unknown = false;      // treat boundaries of superpixels without a plane as occlusions
  bool disparity_band = true;        // also stop at superpixels outside the group's disparity band
  double band_tolerance_px = 1.5;    // band = [min d - tol(min d), max d + tol(max d)], tol(d) = px + rel * d
  double band_tolerance_rel = 0.05;
  // With the band, a superpixel also joins the outline only when its plane agrees (band tolerance) with the
  // disparity of the group's nearest started point: one group may hold objects at different depths.
  bool local_band = true;
  MaskMode mask_mode = MaskMode::kDisparity;
  // Static veto (beyond the paper): a superpixel that holds a tracked point which passed the motion tests,
  // with a disparity agreeing with the superpixel's plane (start tolerance), is static: the search stops on
  // entering it and the outline never includes it. Separates a person from a shelf at the same depth,
  // where no occlusion boundary exists.
  bool static_veto = true;
  // Ground veto (beyond the paper): a superpixel whose plane agrees with the frame's ground plane (fitted to
  // the static points below the horizon, in disparity space: d = a x + b y + c with b > 0) is floor: the
  // search stops on entering it and the outline never includes it. Removes the floor strip around the feet of
  // a person or the wheels of a vehicle, where the object touches the floor and no occlusion boundary exists.
  bool ground_veto = true;
  double ground_tolerance_px = 1.0;      // |plane - ground| at the superpixel's centre ...
  double ground_tolerance_rel = 0.05;    // ... + this fraction of d
  double ground_slope_tolerance = 0.75;  // |b_plane - b_ground| <= this fraction of b_ground (b = 0 never passes)
  // Superpixels without a plane (no SGBM disparity: textureless, or the half-occluded strip to the left of a
  // foreground object) join the outline only when enclosed: from their centre, the first other superpixel
  // left, right, above and below is a member. The half-occluded background strip has background on one side,
  // the floor between a person's legs has floor below it.
  bool enclosed_unknown_only = true;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Optional disparity band for the search (see above); planes are in full-image coordinates.
struct DisparityBand {
  bool enabled = false;
  double lo_px = 0, hi_px = 0;
  const std::vector<DisparityPlane>* planes = nullptr;
  cv::Point origin;                           // full-image position of the label image's top-left pixel
  const std::vector<char>* vetoed = nullptr;  // per label: static superpixel (the search stops before it)
  // Ground plane (full-image coordinates) for the ground veto; nullptr = none. A superpixel whose plane agrees
  // with it counts as outside the band.
  const DisparityPlane* ground = nullptr;
  double ground_tolerance_px = 1.0, ground_tolerance_rel = 0.05, ground_slope_tolerance = 0.75;
};

// True when `plane` (valid) agrees with `ground` at pixel (x, y) of the full image, within the tolerances.
bool is_ground_like(const DisparityPlane& plane, const DisparityPlane& ground, double x, double y, double tolerance_px,
                    double tolerance_rel, double slope_tolerance);

// The ground plane in disparity space from static points (full-image x, y, d) below the horizon row
// `horizon_y`: RANSAC plane with b > min_slope (disparity grows downwards), at least min_inliers inliers.
// Invalid when there is no such plane.
DisparityPlane fit_ground_plane(const std::vector<cv::Point2f>& points_px, const std::vector<float>& disparity_px,
                                double horizon_y, double min_slope = 0.02, int min_inliers = 20);

// The four stop points (ROI-local) of the search from `start` (ROI-local): +x, -x, +y, -y. Each is the last
// pixel before the first occlusion boundary in that direction, or the last pixel of the ROI. With a band,
// also the last pixel before a superpixel outside the band, and never a pixel of a superpixel without plane.
std::array<cv::Point, 4> search_to_occlusion(const cv::Mat& labels, const SuperpixelGraph& graph, cv::Point start,
                                             bool stop_at_unknown, const DisparityBand& band = {});

// The superpixel to start from for a point (full-image coordinates) with disparity d_px; -1 when none agrees.
int choose_start_superpixel(const cv::Mat& labels, cv::Point origin, const std::vector<DisparityPlane>& planes,
                            cv::Point2f point_px, float d_px, const RegionSearchConfig& config);

struct DynamicRegion {
  cv::Rect rectangle;            // full-image coordinates (empty when no point could start)
  std::vector<int> superpixels;  // the flood from the start superpixels (labels of this ROI)
  std::vector<int> start_superpixels;
  std::vector<int> vetoed_superpixels;  // static superpixels (static veto)
  std::vector<cv::Point> stop_points;   // full-image coordinates, 4 per started point
  int started_points = 0;
  double band_lo_px = 0, band_hi_px = 0;  // the disparity band used (when enabled)
};

// points_px/disparity_px: the group's dynamic points (full image). labels/planes/graph: the ROI's
// segmentation (origin = ROI top-left in the full image). static_points_px/static_disparity_px (optional):
// tracked points that passed the motion tests, for the static veto. ground (optional, valid): the ground
// plane for the ground veto. moves_with_background (optional, one flag per superpixel): superpixels whose
// image content moved as the ego-motion predicts for a static surface (the detector's photometric check);
// they are vetoed like static superpixels unless a dynamic point starts from them.
DynamicRegion find_dynamic_region(const cv::Mat& labels, cv::Point origin, const SuperpixelGraph& graph,
                                  const std::vector<DisparityPlane>& planes, const std::vector<cv::Point2f>& points_px,
                                  const std::vector<float>& disparity_px, const RegionSearchConfig& config,
                                  const std::vector<cv::Point2f>& static_points_px = {},
                                  const std::vector<float>& static_disparity_px = {},
                                  const DisparityPlane* ground = nullptr,
                                  const std::vector<char>* moves_with_background = nullptr);

// Sets the region's pixels to `value` in `mask` (full image, CV_8UC1): the rectangle, or the flooded
// superpixels inside the rectangle.
void paint_region(const DynamicRegion& region, const cv::Mat& labels, cv::Point origin, MaskMode mode, cv::Mat& mask,
                  uint8_t value = 255);

// Writes the pixels of one region (region_mask, non-zero) into `instances` (CV_8UC1 of the same size) as
// objects numbered from first_id (capped at 255): with split_side_by_side, the region's 8-connected pieces are
// grouped by overlapping columns (by half the narrower piece: stacked pieces of one upright object stay
// together; pieces side by side are separate objects, e.g. two people in one ROI); pieces under 1/50 of the
// region join the largest. Without splitting the whole region is first_id. Returns the next free id.
int label_region_objects(const cv::Mat& region_mask, bool split_side_by_side, int first_id, cv::Mat instances);

}  // namespace agvslam::dynamic
