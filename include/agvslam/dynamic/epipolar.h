#pragma once
// Epipolar test for moving points (paper 004, III.A, eqs. 1-3):
//   pyramidal Lucas-Kanade tracking of the previous frame's corners into the current left image (with a
//   forward-backward check), a fundamental matrix from the tracks by RANSAC (refitted by least squares on the
//   inliers), and for each track
//     L = F p_prev (eq. 1),  D_epi = |A x + B y + C| / sqrt(A^2 + B^2) (eq. 2),
//     dynamic when D_epi > T_epi = a_epi + b_epi * d (eq. 3), d = disparity at the current point.
// Beyond the paper: an adaptive a_epi from the robust scale of the residuals of this frame
// (a = clamp(k * 1.4826 * median(D_epi), a_epi, a_epi_max)), and a static-camera fallback (when the median
// track length is below min_parallax_px, F is undefined and the track length itself is the residual).

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `tracking`.
struct LkTrackerConfig {
  int window_px = 11;  // LK window side
  int levels = 4;      // pyramid levels above the image (0 = no pyramid): the most that are used
  // Beyond the paper: each frame tracks on as few levels as the motion needs, from min_levels up to `levels`. An
  // LK window of w px follows about (w / 2) * 2^L px of motion on L levels; the fewest levels that follow
  // motion_margin x the largest motion of the previous frame's tracks are used (all of them after a frame without
  // tracks). Every level costs about the same per track: 2 levels instead of 4 is ~40 % less LK.
  int min_levels = 2;  // (above `levels`: `levels`, always)
  double motion_margin = 2.0;
  int max_iterations = 20;
  double epsilon = 0.03;         // LK stop criterion (px)
  double fb_max_error_px = 1.0;  // forward-backward round trip error allowed
  double min_eigen_threshold = 1e-3;
  // Beyond the paper: tracks continue over frames (the multi-frame test needs their history); each frame's
  // quadtree corners are added only farther than min_track_distance_px from every track, up to max_tracks.
  // false: every frame tracks only the previous frame's new corners (as the paper).
  bool persistent = true;
  double min_track_distance_px = 12.0;
  int max_tracks = 600;
  // Beyond the paper: a track with a disparity starts its LK search where the previous frame's ego-motion (constant
  // velocity) puts a static point, when that is more than predict_min_px from where it was. Fast forward motion
  // moves near ground points by tens of px per frame; searched from their old position, LK's coarse levels lock onto
  // the neighbouring period of a repeated pattern (road hatching, rack uprights, floor tiles), the forward-backward
  // check cannot tell, and the slipped track looks like motion off the epipolar line. 0 = off.
  double predict_min_px = 5.0;

  void validate(const std::string& source) const;
  std::string describe() const;
};

class LkTracker {
 public:
  explicit LkTracker(const LkTrackerConfig& config = {});
  const LkTrackerConfig& config() const { return config_; }

  // Builds the LK pyramid of a grey image (reused for tracking into and out of that image): OpenCV's layout with
  // derivatives, image and Scharr derivatives interleaved per level (pyramid[0] is the image itself).
  void build_pyramid(const cv::Mat& grey, std::vector<cv::Mat>& pyramid) const;

  // Tracks prev_pts from the image of prev_pyramid into that of cur_pyramid; ok[i] = 1 when the track
  // converged, stayed inside the image and passed the forward-backward check. levels < 0: config().levels.
  // start: where each search begins in the current image (e.g. where the ego-motion puts a static point), or
  // nullptr for prev_pts; the backward pass then begins at the result minus the same offset.
  void track(const std::vector<cv::Mat>& prev_pyramid, const std::vector<cv::Mat>& cur_pyramid,
             const std::vector<cv::Point2f>& prev_pts, std::vector<cv::Point2f>& cur_pts, std::vector<uint8_t>& ok,
             int levels = -1, const std::vector<cv::Point2f>* start = nullptr);

  // The levels (min_levels..levels) that follow motion_margin x max_motion_px; levels when max_motion_px < 0
  // (unknown).
  int levels_for_motion(double max_motion_px) const;

 private:
  LkTrackerConfig config_;
  std::vector<cv::Point2f> back_pts_;
  std::vector<uint8_t> status_, back_status_;
  std::vector<float> errors_;
};

// params/dynamic.yaml, section `epipolar`.
struct EpipolarTestConfig {
  double a_epi_px = 1.0;             // eq. 3 constant term (px)
  double b_epi = 0.02;               // eq. 3 slope (px of distance per px of disparity)
  double ransac_threshold_px = 1.0;  // RANSAC inlier distance for F
  double ransac_confidence = 0.999;
  int ransac_max_iterations = 500;
  int min_tracks = 15;           // fewer usable tracks: no test (nothing flagged)
  double min_parallax_px = 0.5;  // median track length below this: static camera, D = track length
  bool adaptive = true;          // adapt a_epi to the residual scale of the frame
  double adaptive_k = 3.0;       // a = k * robust sigma ...
  double a_epi_max_px = 3.0;     // ... clamped to [a_epi_px, a_epi_max_px]

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Eq. 1-2: distance (px) of p_cur from the epipolar line F p_prev in the current image.
double epipolar_distance_px(const cv::Matx33d& F, const cv::Point2f& p_prev, const cv::Point2f& p_cur);

struct EpipolarResult {
  bool valid = false;          // false: too few tracks, or F could not be estimated
  bool static_camera = false;  // the median track was shorter than min_parallax_px
  cv::Matx33d F = cv::Matx33d::zeros();
  int inliers = 0;               // tracks within ransac_threshold_px of their line under the final F
  double robust_sigma_px = 0;    // 1.4826 * median(D_epi)
  double a_epi_used_px = 0;      // the constant term actually used this frame
  std::vector<double> d_epi_px;  // per track (0 where not usable)
  std::vector<double> t_epi_px;  // per track threshold
  std::vector<uint8_t> dynamic;  // per track: D_epi > T_epi
};

class EpipolarTest {
 public:
  explicit EpipolarTest(const EpipolarTestConfig& config = {});
  const EpipolarTestConfig& config() const { return config_; }

  // usable[i] == 0 excludes a track (lost by LK). disparity_px[i] <= 0 means unknown (d = 0 in eq. 3).
  void run(const std::vector<cv::Point2f>& prev_pts, const std::vector<cv::Point2f>& cur_pts,
           const std::vector<uint8_t>& usable, const std::vector<float>& disparity_px, EpipolarResult& result);

  // D_epi and the decision of run() for one more track, with the F and threshold of `fitted` (for tracks
  // added after run(), e.g. around dynamic points). False when `fitted` is not valid.
  bool test_track(const EpipolarResult& fitted, const cv::Point2f& prev_px, const cv::Point2f& cur_px,
                  float disparity_px, double* d_epi_px = nullptr, double* t_epi_px = nullptr) const;

 private:
  EpipolarTestConfig config_;
  std::vector<cv::Point2f> prev_used_, cur_used_, prev_inliers_, cur_inliers_;
  std::vector<int> index_;
  std::vector<double> scratch_, lengths_;
  cv::Mat inlier_mask_;
};

// Robust scale of non-negative residuals: 1.4826 * median (the MAD of a zero-centred distribution).
double robust_sigma(std::vector<double>& residuals);

}  // namespace agvslam::dynamic
