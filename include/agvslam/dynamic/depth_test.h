#pragma once
// Depth-consistency test (beyond paper 004; the reprojection idea of paper 001, DM-SLAM).
//
// The epipolar test cannot see motion along the epipolar line (a person walking straight ahead of a forward-
// driving AGV). With stereo, a tracked point has a disparity in both frames, hence a 3-D position in the
// previous camera. The ego-motion T_cur_prev is estimated from all tracks by P3P RANSAC (3-D previous
// points -> 2-D current points) and refined on the inliers; a point is dynamic when its predicted position
// disagrees with what is observed:
//   reprojection offset |pi(T X_prev) - p_cur|          > a_reproj_px + b_reproj * d, or
//   disparity residual  |bf / Z_pred - d_cur|           > a_disp_px  + b_disp  * d.
// The image prediction is made for every previous disparity within the matcher's error (disparity_slack_*) and the
// offset is the smallest over them: driving fast, a near point's prediction moves by several px per px of disparity
// error (KITTI's road at ~7 m, 2.5 m per frame: ~3 px/px), which would flag the static road otherwise.
// As in the epipolar test, the constant terms can adapt to the robust scale of this frame's residuals.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `depth_test`.
struct DepthTestConfig {
  int min_points = 12;            // tracks with both disparities needed to estimate the motion
  double min_disparity_px = 2.0;  // farther points (depth too uncertain) are neither used nor tested
  double ransac_reprojection_px = 2.0;
  int ransac_iterations = 200;  // at most this many 3-track P3P samples (fewer as the inlier ratio allows)
  double ransac_confidence = 0.999;
  double a_reproj_px = 1.5;  // reprojection threshold: constant (px) ...
  double b_reproj = 0.03;    // ... + slope per px of disparity
  double a_disp_px = 1.0;    // disparity residual threshold: constant (px) ...
  double b_disp = 0.03;      // ... + slope per px of disparity (relative depth error)
  // The previous disparity's error the image prediction allows (px): constant + fraction of d (0 / 0: the measured
  // one). Relative, it also covers the motion's scale error (slack_residuals()).
  double disparity_slack_px = 0.5;
  double disparity_slack_rel = 0.08;
  // Tracks whose match is ambiguous are no evidence either way and are dropped (PointTracks): a static point that the
  // motion puts more than leaving_margin_px outside the image cannot have been found inside it, so what LK found from
  // its old position is either something moving with the camera or a slip onto a look-alike (-1 = kept) ...
  double leaving_margin_px = 0;
  // ... and a flagged track more than slip_min_px off its static prediction whose previous patch (2 x slip_half_window
  // + 1 px, scaled by the predicted change of depth) correlates at slip_min_zncc or more with the image there has
  // slipped a period of a repeated pattern (road hatching, rack uprights): the static prediction explains it too
  // (slip_min_px 0 = no such check).
  double slip_min_px = 12;
  double slip_min_zncc = 0.8;
  int slip_half_window = 5;
  bool adaptive = true;  // raise the constants to k * robust sigma of this frame's residuals
  double adaptive_k = 3.0;
  double max_scale = 3.0;  // adaptive constants are at most max_scale x the configured ones
  // With a motion prior (run()'s T_cur_prev_prior), the tracks within ransac_reprojection_px of where it puts them
  // are the inliers when they are at least this fraction of the used tracks: RANSAC is skipped and the least-squares
  // refinement starts from the prior. Otherwise (or 0) PnP RANSAC as without a prior. Only the multi-frame test has
  // a prior (multiframe.prior_min_inlier_fraction sets it there); the per-frame test has none, so params/dynamic.yaml
  // has no such key under depth_test.
  double prior_min_inlier_fraction = 0.0;

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct DepthTestResult {
  bool valid = false;                  // false: too few points, or PnP failed
  SE3d T_cur_prev = SE3d::Identity();  // estimated ego-motion (previous camera -> current camera)
  int used = 0;                        // tracks with both disparities
  int inliers = 0;                     // PnP inliers
  bool from_prior = false;             // the inliers came from the motion prior (no RANSAC)
  double a_reproj_used_px = 0, a_disp_used_px = 0;
  std::vector<double> reprojection_px;        // per track, -1 where not tested
  std::vector<double> disparity_residual_px;  // per track, -1 where not tested (no current disparity)
  std::vector<uint8_t> dynamic;
};

class DepthConsistencyTest {
 public:
  explicit DepthConsistencyTest(const DepthTestConfig& config = {});
  const DepthTestConfig& config() const { return config_; }

  // camera: rectified left camera; bf_px_m = fx * baseline. usable[i] == 0 excludes a track. A track is
  // tested when its previous disparity is >= min_disparity_px; the disparity residual needs the current one.
  // T_cur_prev_prior: a motion known beforehand (see prior_min_inlier_fraction), or nullptr.
  void run(const PinholeCamera& camera, double bf_px_m, const std::vector<cv::Point2f>& prev_pts,
           const std::vector<float>& prev_disparity_px, const std::vector<cv::Point2f>& cur_pts,
           const std::vector<float>& cur_disparity_px, const std::vector<uint8_t>& usable, DepthTestResult& result,
           const SE3d* T_cur_prev_prior = nullptr);

  // Where a point seen at prev_px with prev_disparity_px appears after the motion: false when it has no disparity
  // or lands behind the camera. depth_m: its depth in the current camera.
  static bool predict(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, const cv::Point2f& prev_px,
                      float prev_disparity_px, Eigen::Vector2d& predicted_px, double& depth_m);
  // Residuals of one track under a motion (-1 where not computable: no previous disparity, or no current
  // one for the disparity residual).
  static void residuals(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, const cv::Point2f& prev_px,
                        float prev_disparity_px, const cv::Point2f& cur_px, float cur_disparity_px,
                        double& reprojection_px, double& disparity_residual_px);
  // residuals() with the previous disparity anywhere within its slack (disparity_slack_*): the offsets to the
  // predictions of that interval (the image one to the segment between its ends, nearly straight over a few px).
  void slack_residuals(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev, const cv::Point2f& prev_px,
                       float prev_disparity_px, const cv::Point2f& cur_px, float cur_disparity_px,
                       double& reprojection_px, double& disparity_residual_px) const;
  // The decision of run() for a track with these residuals, using the motion and thresholds of `fitted`
  // (for tracks added after run(), e.g. around dynamic points). disparity_px: the track's disparity.
  bool is_dynamic(const DepthTestResult& fitted, double reprojection_px, double disparity_residual_px,
                  double disparity_px) const;
  // Its image half's threshold: the reprojection offset above which a track with this disparity is dynamic.
  double reprojection_threshold_px(const DepthTestResult& fitted, double disparity_px) const {
    return fitted.a_reproj_used_px + config_.b_reproj * disparity_px;
  }
  // Its depth half: the disparity residual (>= 0: measured) is over the threshold of `fitted`.
  bool disparity_off(const DepthTestResult& fitted, double disparity_residual_px, double disparity_px) const {
    return disparity_residual_px >= 0 && disparity_residual_px > fitted.a_disp_used_px + config_.b_disp * disparity_px;
  }

 private:
  DepthTestConfig config_;
  std::vector<cv::Point3f> object_;
  std::vector<cv::Point2f> image_;
  std::vector<int> index_;
  std::vector<int> inliers_;
  std::vector<double> scratch_;
};

}  // namespace agvslam::dynamic
