// Dense motion check of superpixels on constructed images with a known ego-motion.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "agvslam/dynamic/photometric_check.h"
#include "noise_texture.h"

namespace agvslam::dynamic {
namespace {

using test::noise_texture;

// 200x120 image, 20x20 superpixels (label = row * 10 + col), every plane fronto-parallel at d = 10 px.
struct Scene {
  PinholeCamera camera;
  double bf = 10.0;  // fx 100 px, baseline 0.1 m: d = 10 px is 1 m away
  cv::Mat labels = cv::Mat(120, 200, CV_32SC1);
  std::vector<DisparityPlane> planes = std::vector<DisparityPlane>(60);
  Scene() {
    camera.fx = camera.fy = 100;
    camera.cx = 100;
    camera.cy = 60;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 200; ++x) labels.at<int32_t>(y, x) = (y / 20) * 10 + x / 20;
    for (auto& p : planes) {
      p.valid = true;
      p.c = 10.0;
    }
  }
};

TEST(PhotometricCheck, StaticSurfaceUnderKnownEgoMotionMovesWithTheBackground) {
  const Scene s;
  const cv::Mat prev = noise_texture(200, 120, 3);
  // The camera moves 2 cm to the left: a surface 1 m away shifts 2 px; cur(x) = prev(x + 2).
  cv::Mat cur;
  cv::warpAffine(prev, cur, cv::Matx23d(1, 0, 2, 0, 1, 0), prev.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REFLECT);
  SE3d T_cur_prev = SE3d::Identity();
  T_cur_prev.translation() = Eigen::Vector3d(-0.02, 0, 0);
  // A 40x40 object (superpixels 23, 24, 33, 34) moved 3 px down on its own.
  const cv::Rect object(60, 40, 40, 40);
  cv::Mat moved;
  cv::warpAffine(prev, moved, cv::Matx23d(1, 0, 2, 0, 1, -3), prev.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REFLECT);
  moved(object).copyTo(cur(object));
  std::vector<SuperpixelMotion> motion;
  PhotometricCheckConfig cfg;
  check_superpixel_motion(cur, prev, s.camera, s.bf, T_cur_prev, s.labels, cv::Point(0, 0), s.planes, cfg, motion);
  ASSERT_EQ(motion.size(), 60u);
  for (int k : {23, 24, 33, 34}) {
    EXPECT_GT(motion[static_cast<std::size_t>(k)].apparent_motion_px, 1.5) << k;
    EXPECT_FALSE(motion[static_cast<std::size_t>(k)].moves_with_background) << k;
  }
  for (int k : {0, 11, 17, 45, 58}) {
    EXPECT_LT(motion[static_cast<std::size_t>(k)].apparent_motion_px, 0.3) << k;
    EXPECT_TRUE(motion[static_cast<std::size_t>(k)].moves_with_background) << k;
  }
  // With the wrong ego-motion (identity) the static surface does not match either.
  check_superpixel_motion(cur, prev, s.camera, s.bf, SE3d::Identity(), s.labels, cv::Point(0, 0), s.planes, cfg,
                          motion);
  EXPECT_FALSE(motion[11].moves_with_background);
}

TEST(PhotometricCheck, ExposureChangeAndWeakTextureAndMissingPlanes) {
  Scene s;
  const cv::Mat prev = noise_texture(200, 120, 5);
  cv::Mat cur;
  prev.convertTo(cur, CV_8UC1, 1.0, 12.0);  // +12 grey levels, camera still
  s.planes[5].valid = false;
  cv::Mat flat = cur.clone();
  flat(cv::Rect(140, 100, 20, 20)).setTo(128);  // superpixel 57: no texture
  cv::Mat prev_flat = prev.clone();
  prev_flat(cv::Rect(140, 100, 20, 20)).setTo(128);
  std::vector<SuperpixelMotion> motion;
  check_superpixel_motion(flat, prev_flat, s.camera, s.bf, SE3d::Identity(), s.labels, cv::Point(0, 0), s.planes,
                          PhotometricCheckConfig{}, motion);
  EXPECT_TRUE(motion[12].moves_with_background);  // the offset is removed
  EXPECT_LT(motion[12].apparent_motion_px, 0.2);
  EXPECT_EQ(motion[5].samples, 0);  // no plane: not measured
  EXPECT_LT(motion[5].apparent_motion_px, 0);
  EXPECT_LT(motion[57].apparent_motion_px, 0);  // undecided without texture
  EXPECT_FALSE(motion[57].moves_with_background);
}

}  // namespace
}  // namespace agvslam::dynamic
