#pragma once
// The dynamic-region detector of paper 004 (III.A-B) on consecutive rectified stereo frames:
//
//   previous frame: the tracks (quadtree FAST corners, kept over frames) with their disparity, LK pyramid
//   current frame:  LK pyramid -> LK tracks (forward-backward checked) -> disparity at the tracked points
//                   -> epipolar test (F by RANSAC, T_epi = a + b d, adaptive a)  \  a point is dynamic if
//                   -> depth-consistency test (PnP ego-motion, reprojection and   |  any test says so
//                      disparity residuals)                                      |
//                   -> multi-frame test (each track against its own observation  /
//                      0.15-0.6 s back, verified by LK into that image, not at depth edges: motion along the
//                      optical axis at about the vehicle's speed)
//                   -> [densification around small groups of dynamic points]
//                   -> groups of dynamic points -> dynamic ROIs (> 4 points)
//                   -> per ROI: SGBM on the ROI crop, then (regions.mask_mode)
//                      disparity (default): the object's pixels connected to its points through smooth disparity,
//                        not floor (object_outline.h), its sides re-decided at full resolution (edge_refine.h),
//                        kept when its tracks are not mostly static (or move together) and its content does not
//                        move with the background (photometric check) -> dynamic region;
//                      superpixels / rectangle (the paper): SLIC, disparity planes, boundary types, search to the
//                        occlusion boundaries (+ disparity band, static veto) -> rectangle or superpixel outline
//                   -> objects of the last frame that no region continues coast on their own tracks (detector.coast_*)
//                   -> the left band without stereo, where the camera has hardly translated: what moved there by the
//                      left image alone (band_segmenter.h), joined to the objects it touches or an object of its own
//                   -> DynamicMask; then the tracks that held continue, and quadtree FAST corners of the current
//                      frame fill the places no track covers.
//
// Disparity is computed only where it is used: a block matcher at the points, SGBM inside the ROIs (a
// whole-frame SGBM is available for debugging with detector.full_frame_disparity). The first frame, and any
// frame after reset(), gives an empty mask.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/dynamic/band_segmenter.h"
#include "agvslam/dynamic/boundary.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/disparity_plane.h"
#include "agvslam/dynamic/edge_refine.h"
#include "agvslam/dynamic/epipolar.h"
#include "agvslam/dynamic/multiframe_test.h"
#include "agvslam/dynamic/object_outline.h"
#include "agvslam/dynamic/motion_carve.h"
#include "agvslam/dynamic/photometric_check.h"
#include "agvslam/dynamic/quadtree_fast.h"
#include "agvslam/dynamic/region_search.h"
#include "agvslam/dynamic/roi_grouping.h"
#include "agvslam/dynamic/slic.h"
#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/sparse_stereo.h"
#include "agvslam/stereo/stereo_config.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `detector`.
struct DetectorOptions {
  bool use_epipolar_test = true;      // paper 004's test
  bool use_depth_test = true;         // the depth-consistency test (beyond the paper)
  bool full_frame_disparity = false;  // debugging: whole-frame SGBM instead of points + ROIs
  int max_rois = 8;                   // at most this many ROIs per frame (the largest groups)
  double roi_disparity_margin_px = 8; // ROI SGBM searches [0, max point disparity + margin] (<= configured range)
  double roi_scale = 1.0;             // 1 or 0.5: SGBM and SLIC of the ROIs at this resolution (planes, boundaries
                                      // and regions stay at full resolution)
  // 1 or 2 (roi_scale 1): ROI SGBM on every column but pairs of rows averaged, half the matching work. An
  // upright object's outline is decided by its sides, which keep full horizontal resolution.
  int roi_row_step = 2;
  int roi_row_step_min_area_px = 20000;  // ... for ROIs of at least this many px (smaller ones: every row; 0 = all)
  // mask_mode disparity: ROIs larger than this (px) get their SGBM at half resolution anyway (near objects: the
  // half-resolution block's fattening is small against their width; 0 = never).
  int half_scale_min_area_px = 0;
  // ... and their outline loses this many more pixels at its edge (the half-resolution SGBM block fattens the
  // foreground twice as far in full-resolution pixels).
  int half_scale_erode_px = 0;
  // mask_mode disparity (beyond the paper): an outline that reaches the left or right side of its ROI over at
  // least extend_min_rows rows (the ROI comes from the tracks, and a person's side without corners lies beyond
  // it) is cut there: the ROI is widened on that side by extend_step_m at the outline's depth (at least 16 px),
  // the new strip matched, and the outline redone, up to extend_max_rounds times (0 = off).
  int extend_max_rounds = 2;
  int extend_min_rows = 20;
  double extend_step_m = 0.3;
  // A side is not widened when a static track (tested, not dynamic) lies in the outline within this many px of it:
  // the outline has flooded a static surface at the object's depth (0 = no such check).
  int extend_static_guard_px = 24;
  // StereoSGBM leaves the leftmost num_disparities columns of what it matches without disparity, so a ROI at the
  // left image border (a person entering or leaving there, or passing close in a turn) lost its outline left of
  // x ~ 32-64. With this, such a ROI is matched in images padded on the left (edge replicated): its pixels get a
  // disparity from x = d on, as far as the right image sees them.
  bool pad_left_border = true;
  // SGBM's speckle filter (stereo sgbm.speckle_window_size) on the ROI crops. The outline's flood needs smooth
  // disparity and drops lone specks itself; without the filter the ROIs cost less and the regions are the same
  // (seeds 101-102, all scenes: +1 true, -2 false regions).
  bool roi_speckle_filter = false;
  // Regions of one frame that are stacked (their columns overlap by half the narrower, or by a quarter with one
  // wholly above the other; the vertical gap within T_s = a_s + b_s d of grouping or 0.8 m; together no taller
  // than outline.max_height_m) at agreeing median disparity (grouping t_disp) are one object: the later one takes
  // the earlier one's instance (torso and legs found from separate groups, a ROI extended to the floor).
  bool merge_stacked_regions = true;
  int mask_dilation_px = 0;           // grow the final mask by this many pixels
  // Beyond the paper: objects stand on the floor. A ROI whose lowest point lies above the floor row at the
  // group's disparity (from the frame's ground plane; legs often have no corners) is extended down to it.
  bool extend_to_floor = true;
  // ... and up to this height above the floor row (m; 0 = not): corners seldom reach the head of a person.
  double extend_to_height_m = 1.9;
  // Beyond the paper: a region whose outline falls into pieces side by side (columns not overlapping, e.g. two
  // people walking apart inside one ROI) gives one object per piece in DynamicMask::instances.
  bool split_side_by_side = true;
  // Densification (beyond the paper): a small object gets only a few of the N quadtree points, fewer than a
  // ROI needs. Around each small group (densify_min_seeds .. grouping.min_points - 1) of seed points, up to
  // densify_max_points extra FAST corners (features.min_threshold) of the previous frame within
  // densify_radius_px + densify_radius_disparity_factor * d of the group are tracked and tested with this
  // frame's F, motion and thresholds. Seeds are the points both tests flag (when both ran): a track that slid
  // along an edge can fool one test, rarely both; and those the multi-frame test flags, and those the depth test
  // flags by densify_depth_seed_factor times its threshold. Isolated single points (usually noise) are not densified.
  // The persistent tracks keep tracking.max_tracks full, so densified tracks may go densify_extra_tracks beyond
  // it; those the tests pass as static end with the frame unless densify_keep_static.
  bool densify = true;
  double densify_radius_px = 24;
  double densify_radius_disparity_factor = 1.0;
  int densify_max_points = 24;
  double densify_min_distance_px = 5;  // from existing tracks and from each other
  int densify_min_seeds = 2;           // seed points a group needs to be densified (1: a lone strong seed too)
  // A point only the per-frame depth test flags (a far person walking along the epipolar lines, which the epipolar
  // test cannot see) seeds too when its offset is at least this many times that test's threshold (0 = never).
  double densify_depth_seed_factor = 1.5;
  int densify_extra_tracks = 150;      // tracks densification may add beyond tracking.max_tracks (0: none)
  bool densify_keep_static = false;    // densified tracks the tests pass as static continue into the next frame
  // A densified point has no history, so the multi-frame test cannot see it: a person 7 m away walking along the
  // line of sight moves < 1 px per frame against the static prediction (the per-frame tests pass its new corners),
  // but several px over the multi-frame test's 0.3-0.6 s. With densify_multiframe_levels >= 0 (and a multi-frame
  // reference in this frame), each densified point is also tested against that reference: its current patch is
  // tracked by LK (this many pyramid levels above the full image) into the reference image, starting where a static
  // point at its current disparity would be there; it is dynamic when found farther from that prediction than the
  // multi-frame test's threshold (and not on a depth edge or an ambiguous stereo match, as multiframe.edge_check_*
  // and check_* decide for the tracks). -1 = off.
  int densify_multiframe_levels = 2;
  // ... and only when its offset agrees with its group's (the median of the seeds' reference observations against
  // the same prediction) within max(threshold, this fraction of the group's offset); a group whose seeds did not
  // move against the reference adds no such point.
  double densify_multiframe_agreement = 0.35;
  // The threshold for these points is this many times the multi-frame test's: a whole far surface can be off the
  // prediction by about its threshold (the motion's error at that depth), and a densified point has no history to
  // show it held still.
  double densify_multiframe_factor = 3.0;
  // Objects over frames (beyond the paper, mask_mode disparity): the tracks inside a region's outline belong to
  // its object in the next frame. A group of dynamic points of which at least continue_min_points belong to one
  // object of the previous frame is a ROI even when it is smaller than grouping.min_points (a person who showed
  // only two moving corners this frame is still the person of the last frame). (Seeding the outline with the
  // object's other tracks as well was tried: more false regions on scene2/3/5 than it gained.)
  bool track_objects = true;
  int continue_min_points = 3;
  // Objects coast (beyond the paper, paper 002's mask propagation with the detector's own tracks; needs
  // track_objects): an object kept in at least coast_min_detections frames on its own evidence that has no region
  // in this frame (its movers showed too few dynamic corners: a person turning, slowing, half hidden or passing
  // the image border) is outlined again from its own tracks, those of its last outline tracked into this frame
  // (at least coast_min_tracks, at its depth), in its last rectangle moved with them. It is kept only as a region
  // passes the outline checks and the photometric check (a person who stopped moves with the background and is
  // dropped), for at most coast_max_frames frames in a row (0 = off).
  int coast_max_frames = 4;
  int coast_min_detections = 2;
  int coast_min_tracks = 3;
  double coast_min_area_ratio = 0.5;  // a coasted outline smaller than this part of the object's last one is a
                                      // fragment of it: dropped
  // Beyond the paper: the band x < d at the left border has no stereo match (the right camera does not see it), so
  // no outline reaches there. An object leaving the view to the left moves its pixels into that band, where they
  // were outlined in earlier frames: its last mask (band part included) is carried with the median motion of its
  // tracks (the left image alone), and its pixels that fall into the band join it, or, when no region of this frame
  // continues the object, are its region, for at most band_carry_max_frames frames in a row without a region
  // (0 = off). The object must still move: at least band_carry_min_tracks of its tracks held, band_carry_min_dynamic
  // of them dynamic. An object entering from the left has no earlier pixels there: nothing is carried.
  int band_carry_max_frames = 6;
  int band_carry_min_tracks = 3;
  int band_carry_min_dynamic = 2;
  // Beyond the paper: an object found in the previous frame (on its own evidence, >= 2 frames, not coasted, not cut
  // by the left/right border, its rectangle overlapping no other object's) whose outline grew by more than this ratio
  // in one frame flooded a surface beside it: the outline is cut to the object's last pixels, moved by the median
  // motion of its tracks and grown by growth_margin of its last width / height (+2 px) (0 = off).
  double growth_max_ratio = 1.6;
  double growth_margin = 0.08;
  // Beyond the paper: an outline kept as dynamic that holds clearly static tracks (depth-test offset <=
  // carve_max_offset_px and multi-frame offset <= carve_max_multiframe_px, both tested), each at least
  // carve_min_distance_px from every dynamic point of its group, flooded the surface those tracks lie on (a rack
  // at the person's depth): the outline loses the pixels nearer to such a track than to any of its dynamic points.
  // It needs >= carve_min_tracks such tracks (0 = off). Applied to outlines already kept (see params/dynamic.yaml).
  int carve_min_tracks = 2;
  double carve_max_offset_px = 0.3;
  double carve_max_multiframe_px = 1.0;
  double carve_min_distance_px = 12;
  // Beyond the paper: an object (an instance of the mask) is reported only when its bounding box overlaps, by at
  // least this IoU, one found in the previous frame (a moving object persists; a false region seldom does). The
  // first frame of each object is therefore not reported; unreported objects still confirm the next frame's
  // (0 = off: every object is reported in the frame it is found).
  double confirm_min_box_iou = 0.3;
  int confirm_below_px = 30000;  // ... objects of this many px or more (near ones) are reported at once (0: all wait)
  // ... and so are near objects whose tracks are far off the ego-motion: a ROI's points at a mean disparity of at
  // least confirm_near_min_disparity_px whose outline's tracks have a median depth-test offset of at least
  // confirm_near_min_offset_px, the object holding at least confirm_near_min_px (0 = off). The outline's box must
  // fill at least confirm_near_min_roi_fill of its ROI (a partial outline, such as a torso whose legs took the floor's
  // disparity, is no object yet), and lie less than half inside another object's box of the frame (a fragment).
  double confirm_near_min_disparity_px = 12;
  double confirm_near_min_offset_px = 3.0;
  int confirm_near_min_px = 1000;
  double confirm_near_min_roi_fill = 0.35;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Everything in params/dynamic.yaml: one struct per stage.
struct DynamicDetectorConfig {
  QuadtreeFastConfig features;
  LkTrackerConfig tracking;
  EpipolarTestConfig epipolar;
  DepthTestConfig depth_test;
  MultiFrameTestConfig multiframe;
  RoiGroupingConfig grouping;
  SlicConfig slic;
  PlaneFitConfig planes;
  BoundaryConfig boundaries;
  RegionSearchConfig regions;
  OutlineConfig outline;
  EdgeRefineConfig edge_refine;
  PhotometricCheckConfig photometric;
  MotionCarveConfig motion_carve;
  BandSegmenterConfig band;
  DetectorOptions detector;

  void validate(const std::string& source) const;
  // One line per stage, for the start-up echo.
  std::vector<std::string> describe() const;
};

// Loads params/dynamic.yaml over the defaults (absent keys keep their default). Throws InputError naming the
// file and the field ("epipolar.a_epi_px") for a missing file, bad YAML, an unknown key, or a value of the
// wrong type or out of range.
DynamicDetectorConfig load_dynamic_config(const std::string& path);

// One LK track from the previous frame into the current one.
struct TrackedPoint {
  cv::Point2f prev_px, cur_px;
  float prev_disparity_px = 0, cur_disparity_px = 0;  // 0 = unknown
  bool tracked = false;          // LK converged and passed the forward-backward check
  bool densified = false;        // added around a small group of dynamic points (not a quadtree corner)
  int age = 0;                   // frames the track has been followed before this one (1 = born in the previous)
  double d_epi_px = 0, t_epi_px = 0;
  double reprojection_px = -1, disparity_residual_px = -1;  // depth test, -1 = not tested
  double multiframe_px = -1;     // multi-frame test: offset from the prediction, -1 = not tested
  double multiframe_disparity_residual_px = -1;
  bool dynamic_epipolar = false, dynamic_depth = false, dynamic_multiframe = false;
  bool dynamic = false;          // the union of the enabled tests
  int group = -1;                // index into DetectorResult::rois, -1 = none
};

// What became of an outline (mask_mode disparity): a dynamic region, or why not.
enum class OutlineVerdict {
  kKept,
  kNoSeed,              // no point found a pixel of agreeing disparity
  kTooSmall,            // fewer than outline.min_pixels
  kMostlyStaticTracks,  // the tracks inside it are mostly static (outline.min_dynamic_fraction)
  kTooTall,             // taller than outline.max_height_m
  kMovesWithBackground  // the photometric check found it static (photometric)
};
std::string to_string(OutlineVerdict verdict);

// The segmentation of one dynamic ROI (debugging output; coordinates of `labels` are ROI-local).
struct RoiSegmentation {
  cv::Rect roi;
  std::vector<int> points;                 // indices into DetectorResult::points
  double mean_disparity_px = 0;
  cv::Mat disparity_px;                    // CV_32FC1, ROI size (SGBM on the crop), 0 = none
  cv::Mat labels;                          // CV_32SC1, ROI size
  int superpixels = 0;
  SlicStats slic;
  std::vector<DisparityPlane> planes;      // per superpixel
  std::vector<SuperpixelBoundary> boundaries;
  std::vector<SuperpixelMotion> motion;    // photometric check per superpixel (when enabled)
  cv::Mat outline;                         // CV_8UC1, ROI size: the object's pixels (mask_mode disparity)
  bool half_scale = false;                 // disparity_px came from half-resolution SGBM
  OutlineStats outline_stats;
  SuperpixelMotion outline_motion, outline_motion_multiframe;  // photometric check of the outline (when run)
  MotionCarveStats motion_carve;           // two-motion carving of a kept outline (motion_carve)
  OutlineVerdict outline_verdict = OutlineVerdict::kNoSeed;   // kKept: the outline is a dynamic region
  int object_id = -1;                      // the object over frames (detector.track_objects): continued or new
  bool coasted = false;                    // outlined from the tracks of an object of earlier frames (coast_*)
  DynamicRegion region;
};

struct DynamicMask {
  cv::Mat image;                  // CV_8UC1, 255 = dynamic, the size of the input frame
  cv::Mat instances;              // CV_8UC1, 0 = static, k > 0 = pixel of detected object k (a region, or with
                                  // detector.split_side_by_side one of the side-by-side objects of a region)
  std::vector<cv::Rect> regions;  // the dynamic rectangles (paper's output)
  int pixel_count() const { return image.empty() ? 0 : cv::countNonZero(image); }
};

struct StageTimings {
  double pyramid_ms = 0, tracking_ms = 0, point_disparity_ms = 0, epipolar_ms = 0, depth_test_ms = 0, multiframe_ms = 0,
         densify_ms = 0, grouping_ms = 0, roi_disparity_ms = 0, slic_ms = 0, planes_ms = 0, boundaries_ms = 0, regions_ms = 0,
         motion_carve_ms = 0, band_ms = 0, features_ms = 0, total_ms = 0;
  std::string describe() const;
};

struct DetectorResult {
  std::size_t frame_index = 0;
  int64_t t_ns = 0;
  bool has_previous = false;     // false on the first frame: nothing can be tested
  DynamicMask mask;
  std::vector<TrackedPoint> points;
  std::vector<RoiSegmentation> rois;
  EpipolarResult epipolar;
  DepthTestResult depth;
  MultiFrameResult multiframe;
  BandResult band;               // the left band without stereo (band_segmenter.h)
  int band_joined = 0, band_objects = 0;  // its regions joined to an object of the mask / reported as objects of their own
  // While the AGV drives: the band's candidate movers (BandSegmenter::driving_seeds) / those the tests flagged, which
  // joined the dynamic points.
  int band_driving_seeds = 0, band_driving_dynamic = 0;
  DisparityPlane ground_plane;   // d = a x + b y + c of the floor from the static points (ground veto); may be invalid
  cv::Mat full_disparity_px;     // only with detector.full_frame_disparity
  StageTimings timings;
  int unconfirmed_objects = 0;   // objects found but not reported: nothing overlapped them in the previous frame
                                 // (detector.confirm_min_box_iou)
  int lk_levels = -1;            // the pyramid levels the tracks were followed on (tracking.min_levels; -1: none)

  int dynamic_point_count() const;
};

// detector.confirm_near_*: whether boxes[k] lies at least half inside another non-empty box of `boxes` (a fragment
// beside the object it belongs to, such as an arm outlined apart from its person).
bool lies_half_inside_another(const std::vector<cv::Rect>& boxes, std::size_t k);

// detector.growth_max_ratio: cuts `outline` (CV_8UC1, its top-left pixel at `outline_origin` in the image) to the
// pixels of `last_pixels` (CV_8UC1, non-zero = the object's pixels in the previous frame, its top-left at
// `last_origin`) moved by `shift_px` and grown by `grow_px` on each side (a rectangle). Returns the pixels kept.
int cut_to_moved_pixels(cv::Mat& outline, cv::Point outline_origin, const cv::Mat& last_pixels, cv::Point last_origin,
                        cv::Point shift_px, cv::Size grow_px);

// detector.carve_min_tracks: removes from `outline` (CV_8UC1, its top-left pixel at `outline_origin` in the image)
// every pixel nearer (image distance) to one of `static_px` than to all of `object_px` (image coordinates), a
// Voronoi split between the object's dynamic points and the static tracks of a flooded surface (decided per 4x4
// block by distance transforms, and exactly per pixel in the blocks a cell boundary passes). Returns the pixels kept
// (all of them when either set is empty).
int carve_static_cells(cv::Mat& outline, cv::Point outline_origin, const std::vector<cv::Point2f>& object_px,
                       const std::vector<cv::Point2f>& static_px);

class DynamicDetector {
 public:
  // calibration: of the rectified frames that detect() receives. Validates both configurations
  // (InputError naming the struct and field).
  explicit DynamicDetector(const StereoCalibration& calibration, const DynamicDetectorConfig& config = {},
                           const stereo::StereoConfig& stereo_config = {});

  const DynamicDetectorConfig& config() const { return config_; }
  const stereo::StereoConfig& stereo_config() const { return stereo_config_; }

  // Runs the pipeline on the next frame (CV_8UC1 left/right of the calibration's size). The previous frame is
  // kept internally.
  DetectorResult detect(const StereoFrame& frame);
  // Same, reusing the buffers of `result` (no per-frame allocation once sizes have settled).
  void detect(const StereoFrame& frame, DetectorResult& result);

  // Forgets the previous frame (the next detect() gives an empty mask).
  void reset();

 private:
  // The stages of detect(), in order.
  // Clears the per-frame parts of `result` (a frame of another size than the last one resets the detector).
  void begin_frame(const StereoFrame& frame, DetectorResult& result);
  // LK of the tracks into this frame, their disparities, the epipolar, depth and multi-frame tests.
  void track_and_test(const StereoFrame& frame, DetectorResult& result);
  // result.points from the tests; the dynamic ones into dyn_pts_, dyn_disp_, dyn_index_.
  void collect_points(DetectorResult& result);
  // Eq. 4 grouping of the dynamic points into ROIs, each continuing the previous frame's object most of its points
  // belong to (group_object_).
  void group_dynamic(cv::Size size, DetectorResult& result, std::vector<DynamicGroup>& groups);
  // The floor plane, then each group's outline (and the coasting objects' groups) into result.rois and the mask.
  void outline_groups(const StereoFrame& frame, DetectorResult& result, std::vector<DynamicGroup>& groups,
                      int& next_instance);
  void outline_group(const StereoFrame& frame, DetectorResult& result, const std::vector<DynamicGroup>& groups,
                     std::size_t g, int& next_instance);
  // The left band (carried and segmented regions), the mask's dilation and the objects kept for the next frame.
  void finish_mask(const StereoFrame& frame, DetectorResult& result, int& next_instance);
  // The tracks that continue, this frame's new quadtree corners and their disparities, each track's object.
  void replenish_tracks(const StereoFrame& frame, DetectorResult& result);
  // detector.track_objects with the disparity outline (objects are followed over frames).
  bool tracks_objects() const;

  void densify(const StereoFrame& frame, DetectorResult& result);
  // While the AGV drives, the left strip's candidate movers (BandSegmenter::driving_seeds) that the epipolar or the
  // depth test flags join this frame's dynamic points (band.driving_seed_offset_px).
  void add_band_driving_seeds(const StereoFrame& frame, DetectorResult& result);
  // A point this frame adds beside the tracks (densification, the band's driving seeds), tracked from prev_px to
  // cur_px: the frame's epipolar and depth tests on it; its multi-frame result comes from the caller.
  TrackedPoint tested_new_point(const DetectorResult& result, const cv::Point2f& prev_px, const cv::Point2f& cur_px,
                                float prev_disparity_px, float cur_disparity_px, double multiframe_px,
                                bool dynamic_multiframe) const;
  // Appends such a point to the frame's points and to the track history (and, when dynamic, to dyn_pts_ & co.).
  void append_new_point(DetectorResult& result, const TrackedPoint& p);
  // The union of the enabled tests (detector.use_epipolar_test, use_depth_test) on a point's flags.
  bool flagged_by_enabled_tests(const TrackedPoint& p) const;
  // Appends a point (row `index` of result.points) to the frame's dynamic points: dyn_pts_, dyn_disp_, dyn_index_.
  void add_dynamic_point(const TrackedPoint& p, int index);
  // The multi-frame test of this frame's densified points (extra_*), into extra_mf_ / extra_mf_px_.
  void test_densified_multiframe(const StereoFrame& frame, const DetectorResult& result);
  // The multi-frame test's depth-edge and stereo checks of a point with this disparity (multiframe.edge_check_*,
  // check_*): true when its window straddles a depth edge or its match is missing or ambiguous.
  bool on_depth_edge_or_ambiguous(const StereoFrame& frame, const cv::Point2f& p, float disparity_px);
  void outline_region(const StereoFrame& frame, DetectorResult& result, RoiSegmentation& seg, int& next_instance);
  // Coasting (detector.coast_*): a group per object of the last frame that no region of this frame continues and
  // that still has coast_min_tracks tracks at its depth (seeds appended to dyn_pts_).
  void add_coasting_groups(const DetectorResult& result, cv::Size image_size, std::vector<DynamicGroup>& groups);
  // Objects of the last frame near the left border: their pixels carried into the band x < d (band_carry_*).
  void carry_band_masks(DetectorResult& result, int& next_instance);
  // The band segmenter's regions of this frame: each joins the object of the mask it touches (band.merge_distance_px),
  // or is an object of its own when upright and large enough.
  void add_band_regions(DetectorResult& result, int& next_instance);
  // Pixels `painted` into the band (carried or segmented) for `instance`: a region of their own (new_region), or a part
  // of the region that holds the instance.
  void add_band_rect(DetectorResult& result, const cv::Rect& painted, int instance, bool new_region);
  void clamp_growth(const DetectorResult& result, RoiSegmentation& seg);
  void carve_static(const DetectorResult& result, RoiSegmentation& seg);
  // A kept outline's blocks that moved as a static surface, not with the object (motion_carve.h), are removed.
  void carve_motion(const StereoFrame& frame, const DetectorResult& result, RoiSegmentation& seg);
  // The objects with regions in this frame become objects_.
  void update_objects(const DetectorResult& result);
  // SGBM of one ROI (detector.pad_left_border: in left-padded images near the left border).
  void roi_disparity(const StereoFrame& frame, const cv::Rect& roi, int max_disparity_px, double scale, cv::Mat& out);
  void measure_point_disparities(const StereoFrame& frame, const std::vector<cv::Point2f>& pts, std::vector<float>& out,
                                 const cv::Mat& full_disparity_px);

  StereoCalibration calibration_;
  DynamicDetectorConfig config_;
  stereo::StereoConfig stereo_config_;
  QuadtreeFast features_;
  LkTracker tracker_;
  EpipolarTest epipolar_;
  DepthConsistencyTest depth_test_;
  MultiFrameTest multiframe_;
  TrackHistory history_;  // the tracks' last observations; row i = prev_pts_[i] (then result.points[i])
  Slic slic_;
  Slic slic_half_;  // superpixel size halved, for roi_scale 0.5
  stereo::StereoSgbm sgbm_;
  stereo::SparseStereoMatcher sparse_;
  stereo::SparseStereoMatcher check_sparse_;  // larger window, stricter uniqueness (multiframe.check_*)
  SuperpixelGraph graph_;
  ObjectOutliner outliner_;
  EdgeRefiner edge_refiner_;
  BandSegmenter band_;
  std::vector<BandSeed> driving_seeds_;
  std::vector<cv::Point2f> band_track_cur_;

  bool has_previous_ = false;
  std::vector<cv::Mat> prev_pyramid_, cur_pyramid_;
  std::vector<Corner> corners_;
  std::vector<cv::Rect> prev_object_boxes_, object_boxes_;  // the objects found (reported or not) per frame
  std::vector<int> object_pixels_;
  std::vector<int> box_limits_;
  std::vector<uint8_t> drop_object_;
  void confirm_objects(DetectorResult& result);
  std::vector<int> cell_start_, cell_fill_;   // the tracks binned for the new corners' distance test
  std::vector<cv::Point2f> cell_points_;
  std::vector<cv::Point2f> prev_pts_;        // corners of the previous frame
  std::vector<float> prev_disparity_px_;     // their disparity in the previous frame
  std::vector<cv::Point2f> cur_pts_;
  std::vector<uint8_t> tracked_;
  std::vector<float> cur_disparity_px_;
  std::vector<uint8_t> usable_, keep_, consistent_;
  std::vector<cv::Point2f> new_pts_;
  std::vector<float> new_disp_;
  std::vector<cv::Point2f> dyn_pts_;
  std::vector<float> dyn_disp_;
  std::vector<int> dyn_index_;
  std::vector<cv::Point2f> group_pts_, static_pts_;
  std::vector<float> group_disp_, static_disp_;
  cv::Mat dilated_, small_grey_, small_labels_, reshaped_outline_, clamp_last_, clamp_lut_;
  cv::Mat prev_instances_;               // the previous frame's instances (detector.growth_max_ratio)
  std::vector<int> prev_instance_object_;  // ... and their objects
  cv::Mat prev_left_, prev_right_;            // the previous frame (for densification)
  std::vector<cv::KeyPoint> keypoints_;
  std::vector<cv::Point2f> extra_prev_, extra_cur_;
  std::vector<uint8_t> extra_ok_;
  std::vector<float> extra_prev_disp_, extra_cur_disp_;
  std::vector<cv::Point2f> mf_cur_, mf_ref_, mf_back_, mf_pred_;
  std::vector<int> mf_index_;
  std::vector<uint8_t> mf_status_, mf_back_status_, extra_mf_;
  std::vector<float> mf_errors_;
  std::vector<double> extra_mf_px_;
  std::vector<cv::Point2f> extra_group_motion_;
  std::vector<uint8_t> extra_group_valid_;
  std::vector<float> mf_vx_, mf_vy_;
  std::vector<cv::Mat> mf_cur_pyramid_, mf_ref_pyramid_;
  std::vector<cv::Point2f> seed_pts_;
  std::vector<float> seed_disp_;
  std::vector<int> seed_index_;
  std::vector<char> background_flags_;
  std::vector<int> track_object_;           // per track (row of prev_pts_): object of the previous frame, -1 none
  std::vector<int> group_object_;           // per group: the previous frame's object it continues, -1 none
  std::vector<int> instance_object_;        // per instance id of this frame's mask: object id
  std::vector<uint8_t> instance_near_moving_;  // per instance id: a near outline far off the ego-motion
                                               // (detector.confirm_near_*: reported without confirmation)
  int next_object_id_ = 0;
  // The objects of the last frame that had regions (detector.track_objects), for coasting.
  struct ObjectTrack {
    cv::Rect rect;                   // its region in that frame
    double median_disparity_px = 0;
    int pixels = 0;                  // its outline's pixels in that frame
    int detections = 0;              // frames kept on its own evidence
    int coasted = 0;                 // frames in a row it has coasted since
    int band_frames = 0;             // frames in a row it was only carried in the left band (band_carry_*)
    cv::Rect carry_rect;             // its pixels in that frame, kept near the left band only (band_carry_*) ...
    cv::Mat carry_mask;              // ... CV_8UC1 of carry_rect's size, 255 = the object's
  };
  std::vector<std::pair<int, ObjectTrack>> objects_;  // by object id, ascending
  std::vector<std::pair<int, ObjectTrack>> next_objects_;
  std::vector<int> coast_tracks_;
  std::vector<float> motion_dx_, motion_dy_;  // scratch: tracks' image motion (coasting, band carry, growth cut)
  double carve_ms_ = 0;                       // motion_carve time within one outline_region call
  std::vector<float> carve_offsets_;          // scratch: an object's points' depth-test offsets (motion_carve)
  std::vector<cv::Point2f> carve_static_px_;  // scratch: clearly static tracks inside an outline (carve_min_tracks)
  std::vector<uint8_t> coast_own_;
  struct CarriedObject {
    int id;
    int instance;        // the instance its band pixels were painted with
    bool band_only;      // no region of this frame continues it
    cv::Rect rect;       // the band pixels painted
    int pixels;
  };
  std::vector<CarriedObject> carried_;
  std::vector<int> overlap_count_;  // per instance: carried pixels on it (band regions: pixels, columns near it)
  std::vector<int> band_order_, column_seen_;  // scratch of add_band_regions
  std::vector<cv::Point2f> band_prev_, band_cur_;  // this frame's tracks in the band strip
  cv::Mat carry_lut_;               // instance -> 255 (the object's) / 0
  std::vector<uint8_t> band_only_;  // per entry of next_objects_: only carried in the band this frame
  std::vector<float> inside_offsets_, static_offsets_;
  double static_offset_median_px_ = -1;  // of this frame's static tracks (-1: not computed yet)
  std::vector<uint8_t> coast_group_;  // per group: coasted
  cv::Mat region_mask_;
  cv::Mat padded_left_, padded_right_;
  cv::Mat strip_disparity_, widened_disparity_;
  int roi_max_disparity_px_ = 0;  // the search range of the ROI being outlined (for its widening)
  double last_max_motion_px_ = -1;  // the previous frame's largest track motion (-1: unknown), for its LK levels
  double roi_scale_used_ = 1.0;
  int roi_row_step_used_ = 1;
  double widen_ms_ = 0;           // time spent matching widened strips (counted as ROI disparity)
  struct KeptRegion {
    cv::Rect rect;
    double median_disparity_px;
    int instance;
    std::size_t region_index;  // in result.mask.regions
  };
  std::vector<KeptRegion> kept_regions_;  // this frame's regions (merge_stacked_regions)
};

}  // namespace agvslam::dynamic
