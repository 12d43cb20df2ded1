#include "agvslam/dynamic/depth_test.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "agvslam/dynamic/epipolar.h"

namespace agvslam::dynamic {

namespace {

// The motion of an OpenCV rotation vector and translation.
SE3d pose_of(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_e;
  cv::cv2eigen(R, R_e);
  return make_se3(R_e, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

// The indices of the tracks a motion puts within threshold_px of where they are seen.
void inliers_of(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                const PinholeCamera& camera, const SE3d& T_cur_prev, double threshold_px, std::vector<int>& inliers) {
  inliers.clear();
  const double max_err2 = threshold_px * threshold_px;
  for (std::size_t i = 0; i < object.size(); ++i) {
    const Eigen::Vector3d X_cur = T_cur_prev * Eigen::Vector3d(object[i].x, object[i].y, object[i].z);
    if (!(X_cur.z() > 1e-3)) continue;
    const Eigen::Vector2d error = camera.project(X_cur) - Eigen::Vector2d(image[i].x, image[i].y);
    if (error.squaredNorm() <= max_err2) inliers.push_back(static_cast<int>(i));
  }
}

// PnP RANSAC: P3P (OpenCV's solveP3P) on 3-point samples, each of its solutions scored by the tracks it puts within
// threshold_px (the projection done here, a few ns per track, where cv::solvePnPRansac's projectPoints costs most of
// its time); the sample count adapts to the best inlier ratio as in OpenCV's RANSAC. Fixed seed: reproducible.
// Returns the best motion's inliers (empty when no sample gave a motion).
void ransac_p3p(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                const PinholeCamera& camera, double threshold_px, double confidence, int max_iterations, cv::Mat& rvec,
                cv::Mat& tvec, std::vector<int>& inliers) {
  inliers.clear();
  const int n = static_cast<int>(object.size());
  if (n < 4) return;
  const cv::Matx33d K = camera.K();
  cv::RNG rng(0x5eed);
  std::vector<cv::Point3f> sample_obj(3);
  std::vector<cv::Point2f> sample_img(3);
  std::vector<cv::Mat> rvecs, tvecs;
  std::vector<int> candidate;
  int best_count = 0;
  int needed = max_iterations;
  for (int it = 0; it < needed; ++it) {
    int idx[3];
    for (int k = 0; k < 3; ++k) {
      bool fresh;
      do {
        idx[k] = rng.uniform(0, n);
        fresh = true;
        for (int j = 0; j < k; ++j) fresh = fresh && idx[j] != idx[k];
      } while (!fresh);
      sample_obj[static_cast<std::size_t>(k)] = object[static_cast<std::size_t>(idx[k])];
      sample_img[static_cast<std::size_t>(k)] = image[static_cast<std::size_t>(idx[k])];
    }
    int solutions = 0;
    try {
      solutions = cv::solveP3P(sample_obj, sample_img, K, cv::noArray(), rvecs, tvecs, cv::SOLVEPNP_P3P);
    } catch (const cv::Exception&) {
      solutions = 0;  // degenerate sample (collinear points)
    }
    for (int s = 0; s < solutions; ++s) {
      inliers_of(object, image, camera, pose_of(rvecs[static_cast<std::size_t>(s)], tvecs[static_cast<std::size_t>(s)]),
                 threshold_px, candidate);
      if (static_cast<int>(candidate.size()) <= best_count) continue;
      best_count = static_cast<int>(candidate.size());
      inliers.swap(candidate);
      rvecs[static_cast<std::size_t>(s)].copyTo(rvec);
      tvecs[static_cast<std::size_t>(s)].copyTo(tvec);
      // Samples needed for `confidence` that one is all inliers: log(1 - p) / log(1 - w^3), at most max_iterations.
      const double w = static_cast<double>(best_count) / n;
      const double log_miss = std::log(std::max(1.0 - w * w * w, 1e-12));
      needed = std::min(max_iterations, static_cast<int>(std::ceil(std::log(1.0 - confidence) / log_miss)));
    }
  }
}

// The result before a motion is fitted: no motion, every track untested, the configured thresholds.
void reset(DepthTestResult& result, std::size_t n, const DepthTestConfig& config) {
  result.valid = false;
  result.T_cur_prev = SE3d::Identity();
  result.used = 0;
  result.inliers = 0;
  result.from_prior = false;
  result.a_reproj_used_px = config.a_reproj_px;
  result.a_disp_used_px = config.a_disp_px;
  result.reprojection_px.assign(n, -1.0);
  result.disparity_residual_px.assign(n, -1.0);
  result.dynamic.assign(n, 0);
}

// The prior's inliers, as RANSAC would count them for that motion, and the prior as rvec / tvec, when they are at
// least min_points (and 6) and prior_min_inlier_fraction of the `used` tracks; false (no inliers) otherwise.
bool inliers_of_prior(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                      const PinholeCamera& camera, const SE3d& T_cur_prev_prior, const DepthTestConfig& config,
                      int used, cv::Mat& rvec, cv::Mat& tvec, std::vector<int>& inliers) {
  inliers_of(object, image, camera, T_cur_prev_prior, config.ransac_reprojection_px, inliers);
  if (static_cast<int>(inliers.size()) < std::max(6, config.min_points) ||
      static_cast<double>(inliers.size()) < config.prior_min_inlier_fraction * static_cast<double>(used)) {
    inliers.clear();
    return false;
  }
  cv::Matx33d R_p;
  cv::eigen2cv(Eigen::Matrix3d(T_cur_prev_prior.linear()), R_p);
  const Eigen::Vector3d t_p = T_cur_prev_prior.translation();
  cv::Rodrigues(R_p, rvec);
  tvec = (cv::Mat_<double>(3, 1) << t_p.x(), t_p.y(), t_p.z());
  return true;
}

// Least-squares refinement of rvec / tvec on the inliers.
void refine_on_inliers(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
                       const std::vector<int>& inliers, const cv::Matx33d& K, cv::Mat& rvec, cv::Mat& tvec) {
  std::vector<cv::Point3f> obj_in;
  std::vector<cv::Point2f> img_in;
  obj_in.reserve(inliers.size());
  img_in.reserve(inliers.size());
  for (int k : inliers) {
    obj_in.push_back(object[static_cast<std::size_t>(k)]);
    img_in.push_back(image[static_cast<std::size_t>(k)]);
  }
  cv::solvePnPRefineLM(obj_in, img_in, K, cv::noArray(), rvec, tvec);
}

// The thresholds' constants for this frame: the configured ones, or with `adaptive` adaptive_k x the robust sigma of
// the tested tracks' residuals, between the configured constant and max_scale times it.
void set_constants(const DepthTestConfig& config, const std::vector<int>& tested, std::vector<double>& scratch,
                   DepthTestResult& result) {
  double a_reproj = config.a_reproj_px, a_disp = config.a_disp_px;
  if (config.adaptive) {
    scratch.clear();
    for (int idx : tested) scratch.push_back(result.reprojection_px[static_cast<std::size_t>(idx)]);
    a_reproj = std::clamp(config.adaptive_k * robust_sigma(scratch), config.a_reproj_px,
                          config.max_scale * config.a_reproj_px);
    scratch.clear();
    for (int idx : tested) {
      const double r = result.disparity_residual_px[static_cast<std::size_t>(idx)];
      if (r >= 0) scratch.push_back(r);
    }
    if (!scratch.empty()) {
      a_disp =
          std::clamp(config.adaptive_k * robust_sigma(scratch), config.a_disp_px, config.max_scale * config.a_disp_px);
    }
  }
  result.a_reproj_used_px = a_reproj;
  result.a_disp_used_px = a_disp;
}

}  // namespace

DepthConsistencyTest::DepthConsistencyTest(const DepthTestConfig& config) : config_(config) {
  config_.validate("DepthTestConfig");
}

void DepthConsistencyTest::run(const PinholeCamera& camera, double bf_px_m, const std::vector<cv::Point2f>& prev_pts,
                               const std::vector<float>& prev_disparity_px, const std::vector<cv::Point2f>& cur_pts,
                               const std::vector<float>& cur_disparity_px, const std::vector<uint8_t>& usable,
                               DepthTestResult& result, const SE3d* T_cur_prev_prior) {
  const std::size_t n = prev_pts.size();
  CV_Assert(cur_pts.size() == n && usable.size() == n && prev_disparity_px.size() == n && cur_disparity_px.size() == n);
  reset(result, n, config_);
  if (!(bf_px_m > 0) || !camera.valid()) return;

  // The tested tracks: their previous 3-D points and current image points.
  object_.clear();
  image_.clear();
  index_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!usable[i] || !(prev_disparity_px[i] >= config_.min_disparity_px)) continue;
    const double z = bf_px_m / prev_disparity_px[i];
    object_.emplace_back(static_cast<float>((prev_pts[i].x - camera.cx) / camera.fx * z),
                         static_cast<float>((prev_pts[i].y - camera.cy) / camera.fy * z), static_cast<float>(z));
    image_.push_back(cur_pts[i]);
    index_.push_back(static_cast<int>(i));
  }
  result.used = static_cast<int>(index_.size());
  if (result.used < config_.min_points) return;

  // The motion: the prior's when enough tracks agree with it, else P3P RANSAC's; refined on its inliers.
  cv::Mat rvec, tvec;
  inliers_.clear();
  result.from_prior =
      T_cur_prev_prior && config_.prior_min_inlier_fraction > 0 &&
      inliers_of_prior(object_, image_, camera, *T_cur_prev_prior, config_, result.used, rvec, tvec, inliers_);
  if (!result.from_prior) {
    ransac_p3p(object_, image_, camera, config_.ransac_reprojection_px, config_.ransac_confidence,
               config_.ransac_iterations, rvec, tvec, inliers_);
  }
  if (static_cast<int>(inliers_.size()) < 6) return;
  refine_on_inliers(object_, image_, inliers_, camera.K(), rvec, tvec);
  result.inliers = static_cast<int>(inliers_.size());
  result.T_cur_prev = pose_of(rvec, tvec);
  result.valid = true;

  // Residuals of every tested track, then the (adaptive) thresholds and the decisions.
  for (int idx : index_) {
    const std::size_t i = static_cast<std::size_t>(idx);
    slack_residuals(camera, bf_px_m, result.T_cur_prev, prev_pts[i], prev_disparity_px[i], cur_pts[i],
                    cur_disparity_px[i], result.reprojection_px[i], result.disparity_residual_px[i]);
  }
  set_constants(config_, index_, scratch_, result);
  for (int idx : index_) {
    const std::size_t i = static_cast<std::size_t>(idx);
    result.dynamic[i] = is_dynamic(result, result.reprojection_px[i], result.disparity_residual_px[i],
                                   cur_disparity_px[i] > 0 ? cur_disparity_px[i] : prev_disparity_px[i]);
  }
}

void DepthConsistencyTest::residuals(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                     const cv::Point2f& prev_px, float prev_disparity_px, const cv::Point2f& cur_px,
                                     float cur_disparity_px, double& reprojection_px, double& disparity_residual_px) {
  reprojection_px = -1;
  disparity_residual_px = -1;
  if (!(prev_disparity_px > 0)) return;
  Eigen::Vector2d uv;
  double depth_m = 0;
  if (!predict(camera, bf_px_m, T_cur_prev, prev_px, prev_disparity_px, uv, depth_m)) {
    reprojection_px = 1e6;  // behind the camera under the estimated motion: inconsistent
    return;
  }
  reprojection_px = std::hypot(uv.x() - cur_px.x, uv.y() - cur_px.y);
  if (cur_disparity_px > 0) disparity_residual_px = std::abs(bf_px_m / depth_m - cur_disparity_px);
}

void DepthConsistencyTest::slack_residuals(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                           const cv::Point2f& prev_px, float prev_disparity_px,
                                           const cv::Point2f& cur_px, float cur_disparity_px, double& reprojection_px,
                                           double& disparity_residual_px) const {
  // Only the image offset: scaling the previous depth by (1 + e) moves the prediction as scaling the translation by
  // 1 / (1 + e) would, so the slack also covers the motion's scale error while it hides motion along the viewing ray
  // of the order of e times the frame's translation only. The disparity residual keeps its own thresholds (a_disp_px,
  // b_disp): a slack there would hide e times the depth.
  const double slack = config_.disparity_slack_px + config_.disparity_slack_rel * prev_disparity_px;
  residuals(camera, bf_px_m, T_cur_prev, prev_px, prev_disparity_px, cur_px, cur_disparity_px, reprojection_px,
            disparity_residual_px);
  if (!(slack > 0) || !(prev_disparity_px > 0) || reprojection_px < 0) return;
  // The interval's far end stays at half the disparity at most (a point twice as far is no matching error).
  const float d_far = static_cast<float>(std::max(0.5 * prev_disparity_px, prev_disparity_px - slack));
  const float d_near = static_cast<float>(prev_disparity_px + slack);
  Eigen::Vector2d p_far, p_near;
  double z_far_m = 0, z_near_m = 0;
  if (!predict(camera, bf_px_m, T_cur_prev, prev_px, d_far, p_far, z_far_m) ||
      !predict(camera, bf_px_m, T_cur_prev, prev_px, d_near, p_near, z_near_m)) {
    return;
  }
  const Eigen::Vector2d c(cur_px.x, cur_px.y);
  const Eigen::Vector2d seg = p_near - p_far;
  const double len2 = seg.squaredNorm();
  const double s = len2 > 0 ? std::clamp((c - p_far).dot(seg) / len2, 0.0, 1.0) : 0.0;
  reprojection_px = std::min(reprojection_px, (p_far + s * seg - c).norm());
}

bool DepthConsistencyTest::predict(const PinholeCamera& camera, double bf_px_m, const SE3d& T_cur_prev,
                                   const cv::Point2f& prev_px, float prev_disparity_px, Eigen::Vector2d& predicted_px,
                                   double& depth_m) {
  if (!(prev_disparity_px > 0)) return false;
  const double z = bf_px_m / prev_disparity_px;
  const Eigen::Vector3d X((prev_px.x - camera.cx) / camera.fx * z, (prev_px.y - camera.cy) / camera.fy * z, z);
  const Eigen::Vector3d Xc = T_cur_prev * X;
  if (!(Xc.z() > 1e-3)) return false;
  predicted_px = Eigen::Vector2d(camera.fx * Xc.x() / Xc.z() + camera.cx, camera.fy * Xc.y() / Xc.z() + camera.cy);
  depth_m = Xc.z();
  return true;
}

bool DepthConsistencyTest::is_dynamic(const DepthTestResult& fitted, double reprojection_px,
                                      double disparity_residual_px, double disparity_px) const {
  if (!fitted.valid || reprojection_px < 0) return false;
  const bool off_2d = reprojection_px > reprojection_threshold_px(fitted, disparity_px);
  return off_2d || disparity_off(fitted, disparity_residual_px, disparity_px);
}

}  // namespace agvslam::dynamic
