#pragma once
// Moving objects in the left band without stereo (beyond paper 004).
//
// A pixel of the left image at x < d has no match in the right image: SGBM gives it no disparity, so no outline of
// the detector reaches it, and a person stepping into view at the left border is a sliver in that band for several
// frames (an AGV waiting while a person crosses). The left image alone must then tell what moved.
//
// Without depth, the position in the previous image of a static point seen at pixel p is known only up to its
// epipolar segment: the positions of static points at every disparity in [0, max_disparity_px] along p's ray, moved
// with the ego-motion T_cur_prev. When the camera has hardly translated since the last frame (an AGV waiting at a
// crossing, or turning on the spot) that segment is short, and
//  - seeds: the detector's tracks in the strip x < strip_px, and FAST corners of the current image in the cells of
//    the strip that hold no track, tracked back into the previous image by pyramidal LK (forward-backward
//    checked), whose previous position lies farther than seed_offset_px from the segment (none on pixels already
//    masked), are moving points;
//  - evidence: around the seeds, each pixel's photometric error (the 5x5 mean absolute difference to the previous
//    image) under the motion of its nearest seeds (the least over the nearest `nearest_seeds`) is compared with the
//    least error of a static point anywhere on its segment (sampled every segment_step_px);
//  - regions: the pixels where a seed's motion fits (error <= max_object_error_dn) and fits better by more than
//    evidence_dn grey levels (the difference smoothed over 5x5), closed over close_px, the connected parts holding a
//    seed, inside the strip; rows that reach within edge_fill_px of the image's left edge are filled to it.
// Frames whose segments are longer than max_static_segment_px somewhere in the strip are skipped: there a static
// point at some depth could explain a few pixels of motion, and textured surfaces next to depth edges would pass
// for movers; there driving_seeds() gives only candidate movers (corners off their segments) for the caller's own
// motion tests. The caller decides what a region becomes (DynamicDetector: the band part of an object of its mask
// that the region touches, or an upright object of its own).

#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/dynamic/epipolar.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `band`.
struct BandSegmenterConfig {
  bool enabled = true;
  int strip_px = 64;                   // the strip at the left border searched (the stereo search range)
  double max_disparity_px = 64;        // static points up to this disparity (nearest depth) explain a motion
  double max_static_segment_px = 4.0;  // frames whose static segments are longer somewhere in the strip: skipped
  double segment_step_px = 0.5;        // the static segment is sampled at this spacing (at least its two ends)
  int border_px = 5;                   // corners at least this far from the image edges (the LK window)
  int fast_threshold = 10;             // FAST threshold (grey levels) for the strip's corners
  int cell_px = 12;                    // the strongest corner per cell of this size that holds no track
  double seed_offset_px = 1.5;         // a corner whose previous position is farther from its segment is a seed
  int min_seeds = 2;                   // fewer seeds in the strip: nothing is segmented
  int max_seeds = 16;                  // the seeds farthest off their segments, at most this many
  int nearest_seeds = 3;               // a pixel's object hypotheses: the motions of its nearest seeds
  double evidence_dn = 1.5;            // grey levels (5x5 mean absolute difference) a seed's motion must fit better
  double max_object_error_dn = 8.0;    // ... and fit at all: its error at most this (the background a mover uncovers
                                       // fits neither hypothesis, the static one worse)
  int edge_fill_px = 6;                // rows of a region reaching this close to the image's left edge reach it
                                       // (the 5x5 windows cannot judge the last columns)
  int reach_px = 48;                   // a seed's motion is a pixel's hypothesis this far from the seed at most
  int close_px = 21;                   // morphological closing of the evidence (diameter, px)
  int min_pixels = 300;                // a region touching no object of the mask: at least this many px ...
  int min_height_px = 48;              // ... at least this tall and taller than wide (a person, not a shadow)
  int merge_distance_px = 3;           // a region within this distance of an object of the mask joins it ...
  int stack_gap_px = 80;               // ... and so does one above or below it within this gap, over at least half
                                       // of the region's columns (a person's legs below its torso; 0 = only touching)
  // While the camera translates (segments longer than max_static_segment_px: segment() skips the frame), the strip's
  // corners in cells holding no track, tracked back, whose previous position lies more than driving_seed_offset_px
  // off their segment are candidate movers for the caller's own tests (driving_seeds(); 0 = off).
  double driving_seed_offset_px = 3.0;
  int driving_cell_px = 12;  // ... one corner per cell of this size (a person stepping in spans 40-100 px)

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct BandSeed {
  cv::Point2f cur_px, prev_px;  // the corner in the current image and where LK found it in the previous one
  double offset_px = 0;         // distance of prev_px from the corner's static segment
};

struct BandRegion {
  cv::Rect rect;  // bounding box in the image
  cv::Mat mask;   // CV_8UC1 of rect's size, 255 = the region's pixels
  int pixels = 0;
  std::vector<int> seeds;  // indices into BandResult::seeds lying in it
};

struct BandResult {
  bool ran = false;               // the frame was segmented (enabled, ego-motion given, segments short enough)
  double static_segment_px = -1;  // the longest static segment in the strip (-1: not computed)
  int tracks = 0;                 // the caller's tracks in the strip, tested as they are
  int corners = 0;                // corners tracked back
  std::vector<BandSeed> seeds;
  std::vector<BandRegion> regions;
};

class BandSegmenter {
 public:
  explicit BandSegmenter(const BandSegmenterConfig& config = {});
  const BandSegmenterConfig& config() const { return config_; }

  // The length (px) of the segment of static positions in the previous image of a point seen at (u, v) now:
  // disparities 0 (infinity) to max_disparity_px, with T_cur_prev the camera's motion (maps points of the previous
  // camera frame into the current one).
  double static_segment_length(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, double u,
                               double v) const;
  // Distance (px) of prev_px from that segment of the point seen at cur_px.
  double static_segment_distance(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                 const cv::Point2f& cur_px, const cv::Point2f& prev_px) const;

  // The longest static segment over the strip's corners and the middle of its sides (the strip is where the
  // segments are longest: farthest from the focus of expansion of forward motion).
  double longest_static_segment(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                cv::Size image) const;

  // Candidate movers in the strip while the camera translates (a person stepping in from the left border while
  // the AGV drives, whom no track has reached yet): the strongest FAST corner of each strip cell that holds none of
  // the caller's current tracks (track_cur), tracked back into the previous image, whose previous position lies
  // more than driving_seed_offset_px off its static segment (no static point at any depth explains it). Nothing
  // (false) when disabled or when the segments are short enough for segment() to run on this frame.
  bool driving_seeds(const cv::Mat& cur_left, const std::vector<cv::Mat>& cur_pyramid,
                     const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels,
                     const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                     const std::vector<cv::Point2f>& track_cur, std::vector<BandSeed>& seeds);

  // cur_left / prev_left: CV_8UC1 images of the current and the previous frame; cur_pyramid / prev_pyramid their
  // LK pyramids (LkTracker::build_pyramid), tracked back with `tracker` on `lk_levels` levels (< 0: its default);
  // masked: CV_8UC1 of the image size (non-zero = already dynamic: no seeds there, regions stop there);
  // track_prev / track_cur: correspondences the caller has already (its LK tracks, any part of the image).
  void segment(const cv::Mat& cur_left, const cv::Mat& prev_left, const std::vector<cv::Mat>& cur_pyramid,
               const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels, const PinholeCamera& camera,
               double bf_px_m, const SE3d& T_cur_prev, const cv::Mat& masked,
               const std::vector<cv::Point2f>& track_prev, const std::vector<cv::Point2f>& track_cur, BandResult& out);

 private:
  // The strongest FAST corner (config_.fast_threshold) of each strip cell (cell_px) that holds none of occupied_px, at
  // least border_px from the image's edges and not on masked pixels (masked may be empty); into corners_.
  void untracked_strip_corners(const cv::Mat& cur_left, const cv::Mat& masked,
                               const std::vector<cv::Point2f>& occupied_px, int cell_px);

  // segment()'s steps. The seeds: the caller's tracks in the strip and the untracked cells' corners whose previous
  // position lies off their static segment (at most max_seeds, the farthest off).
  void collect_seeds(const cv::Mat& cur_left, const std::vector<cv::Mat>& cur_pyramid,
                     const std::vector<cv::Mat>& prev_pyramid, LkTracker& tracker, int lk_levels,
                     const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, const cv::Mat& masked,
                     const std::vector<cv::Point2f>& track_prev, const std::vector<cv::Point2f>& track_cur,
                     BandResult& out);
  // The area searched, and the seeds' distinct motions (flows_, flow_of_).
  cv::Rect search_area(const std::vector<BandSeed>& seeds, cv::Size image);
  // The static hypothesis' error over the area (static_error_): the least over samples of the static segment.
  void static_hypothesis(const cv::Mat& cur_left, const cv::Mat& prev_left, const PinholeCamera& camera, double bf_px_m,
                         const SE3d& T_cur_prev, const cv::Rect& area, double longest);
  // Each seed motion's error (seed_error_), within reach_px of its seeds.
  void seed_hypotheses(const cv::Mat& cur_left, const cv::Mat& prev_left, const cv::Rect& area,
                       const std::vector<BandSeed>& seeds);
  // Static minus object error per pixel (evidence_).
  void evidence(const cv::Rect& area, const std::vector<BandSeed>& seeds);
  // The evidence thresholded, closed, kept inside the strip and off masked pixels (binary_).
  void binarize(const cv::Rect& area, int strip, const cv::Mat& masked);
  // Its connected parts that hold a seed, into out.regions.
  void seeded_regions(const cv::Rect& area, BandResult& out);

  BandSegmenterConfig config_;
  std::vector<cv::Point2f> flows_;  // the seeds' distinct motions (quarter px) ...
  std::vector<int> flow_of_;        // ... and each seed's
  std::vector<std::pair<float, int>> by_distance_;
  std::vector<int> block_flows_;
  std::vector<cv::KeyPoint> keypoints_;
  std::vector<cv::Point2f> corners_, back_;
  std::vector<uint8_t> ok_, tracked_cell_;
  std::vector<int> best_corner_;
  std::vector<cv::Mat> seed_error_;
  cv::Mat diff_, blurred_, static_error_, evidence_, binary_, outside_, distance_, labels_;
};

}  // namespace agvslam::dynamic
