// Two-motion carving of an outline on constructed images with a known ego-motion.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/motion_carve.h"
#include "noise_texture.h"

namespace agvslam::dynamic {
namespace {

using test::noise_texture;

// 240x160 images; every surface fronto-parallel at d = 10 px (fx 100, baseline 0.1 m: 1 m away). The camera moves
// 2 cm to the left, so the static background shifts 2 px: cur(x) = prev(x + 2). An object of 40x60 px at the same
// depth (no disparity step separates it from the background) moved 6 px to the right on its own: cur(x) =
// prev(x - 6) there. The outline flooded the background around it: a 120x100 rectangle.
struct Scene {
  PinholeCamera camera;
  double bf = 10.0;
  SE3d T_cur_prev = SE3d::Identity();
  cv::Mat prev, cur;
  cv::Rect object{100, 50, 40, 60};
  cv::Rect roi{60, 30, 140, 120};
  cv::Rect flooded{70, 40, 120, 100};  // in the image
  cv::Mat disparity_px, outline;       // ROI-local
  std::vector<cv::Point2f> object_points;
  explicit Scene(uint32_t seed = 7) {
    camera.fx = camera.fy = 100;
    camera.cx = 120;
    camera.cy = 80;
    T_cur_prev.translation() = Eigen::Vector3d(-0.02, 0, 0);
    prev = noise_texture(240, 160, seed);
    cv::warpAffine(prev, cur, cv::Matx23d(1, 0, 2, 0, 1, 0), prev.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REFLECT);
    cv::Mat moved;
    cv::warpAffine(prev, moved, cv::Matx23d(1, 0, -6, 0, 1, 0), prev.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REFLECT);
    moved(object).copyTo(cur(object));
    disparity_px = cv::Mat(roi.size(), CV_32FC1, cv::Scalar(10.0f));
    outline = cv::Mat::zeros(roi.size(), CV_8UC1);
    outline(flooded - roi.tl()).setTo(255);
    for (int y = object.y + 8; y < object.br().y - 8; y += 11) {
      for (int x = object.x + 8; x < object.br().x - 8; x += 11)
        object_points.emplace_back(static_cast<float>(x), static_cast<float>(y));
    }
  }
  MotionCarveStats carve(const MotionCarveConfig& config, cv::Point2f motion = {6, 0}, double separation = 8.0) {
    return carve_by_motion(cur, prev, camera, bf, T_cur_prev, motion, separation, object_points, disparity_px, roi.tl(),
                           config, outline);
  }
  // Outline pixels inside the object / outside it.
  int on_object() const { return cv::countNonZero(outline(object - roi.tl())); }
  int off_object() const { return cv::countNonZero(outline) - on_object(); }
};

TEST(MotionCarve, BackgroundFloodedAtTheObjectsDepthIsCarvedAndTheObjectStays) {
  Scene s;
  const int flooded_off_object = s.off_object();
  ASSERT_EQ(s.on_object(), s.object.area());
  const MotionCarveStats st = s.carve(MotionCarveConfig{});
  EXPECT_TRUE(st.ran);
  EXPECT_GT(st.blocks_tested, 50);
  EXPECT_GT(st.blocks_static, 30);
  // The object keeps its pixels but for blocks straddling its edge that are mostly background (12 px blocks).
  EXPECT_GE(s.on_object(), 0.85 * s.object.area()) << s.on_object();
  // What is left of the background: only blocks straddling the object's edge (within one block of it).
  EXPECT_LT(s.off_object(), flooded_off_object / 4) << "off " << s.off_object() << " of " << flooded_off_object;
  cv::Mat far_from_object = s.outline.clone();
  const cv::Rect near =
      cv::Rect(s.object.x - 12, s.object.y - 12, s.object.width + 24, s.object.height + 24) - s.roi.tl();
  far_from_object(near).setTo(0);
  EXPECT_EQ(cv::countNonZero(far_from_object), 0);
  EXPECT_EQ(st.pixels_removed, s.flooded.area() - cv::countNonZero(s.outline));
}

TEST(MotionCarve, NothingIsCarvedWhenTheHypothesesAgreeOrCannotBeTold) {
  // The object's tracks are within min_separation_px of the ego-motion: not run.
  {
    Scene s;
    const MotionCarveStats st = s.carve(MotionCarveConfig{}, {6, 0}, 1.0);
    EXPECT_FALSE(st.ran);
    EXPECT_EQ(cv::countNonZero(s.outline), s.flooded.area());
  }
  // Disabled.
  {
    Scene s;
    MotionCarveConfig cfg;
    cfg.enabled = false;
    EXPECT_FALSE(s.carve(cfg).ran);
    EXPECT_EQ(cv::countNonZero(s.outline), s.flooded.area());
  }
  // No texture anywhere: every block is undecided.
  {
    Scene s;
    s.prev.setTo(90);
    s.cur.setTo(90);
    const MotionCarveStats st = s.carve(MotionCarveConfig{});
    EXPECT_TRUE(st.ran);
    EXPECT_EQ(st.blocks_tested, 0);
    EXPECT_EQ(cv::countNonZero(s.outline), s.flooded.area());
  }
  // The object's motion is the background's (+-2 px search): the object hypothesis fits the background as well.
  {
    Scene s;
    const MotionCarveStats st = s.carve(MotionCarveConfig{}, {-2, 0});
    EXPECT_EQ(st.blocks_static, 0);
    EXPECT_EQ(cv::countNonZero(s.outline), s.flooded.area());
  }
}

TEST(MotionCarve, TheWrongEgoMotionCarvesNothingAndPartsWithoutObjectPointsGo) {
  // With the wrong ego-motion (the camera still) the static hypothesis fits nothing: nothing is carved.
  {
    Scene s;
    s.T_cur_prev = SE3d::Identity();
    const MotionCarveStats st = s.carve(MotionCarveConfig{});
    EXPECT_EQ(st.blocks_static, 0);
    EXPECT_EQ(cv::countNonZero(s.outline), s.flooded.area());
  }
  // A second flooded patch joined to the object only through background: once the background is carved it is cut
  // off from the object's points and goes with it, even where its own blocks were undecided (no texture).
  {
    Scene s;
    const cv::Rect patch(172, 122, 16, 16);  // inside the flood, far from the object
    s.cur(patch).setTo(200);
    s.prev(cv::Rect(patch.x + 2, patch.y, patch.width, patch.height)).setTo(200);
    const MotionCarveStats st = s.carve(MotionCarveConfig{});
    EXPECT_GT(st.blocks_static, 30);
    EXPECT_EQ(cv::countNonZero(s.outline(patch - s.roi.tl())), 0);
    EXPECT_GE(s.on_object(), 0.85 * s.object.area());
  }
}

TEST(MotionCarveConfig, BadValuesNameTheField) {
  auto field_of = [](const MotionCarveConfig& c) -> std::string {
    try {
      c.validate("params/dynamic.yaml");
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(field_of(MotionCarveConfig{}), "");
  MotionCarveConfig c;
  c.block_px = 1;
  EXPECT_NE(field_of(c).find("motion_carve.block_px"), std::string::npos) << field_of(c);
  c = MotionCarveConfig{};
  c.sample_step_px = 20;
  EXPECT_NE(field_of(c).find("motion_carve.sample_step_px"), std::string::npos);
  c = MotionCarveConfig{};
  c.max_static_ratio = 0;
  EXPECT_NE(field_of(c).find("motion_carve.max_static_ratio"), std::string::npos);
  c = MotionCarveConfig{};
  c.min_separation_px = -1;
  EXPECT_NE(field_of(c).find("motion_carve.min_separation_px"), std::string::npos);
  c = MotionCarveConfig{};
  c.search_px = 9;
  EXPECT_NE(field_of(c).find("motion_carve.search_px"), std::string::npos);
}

}  // namespace
}  // namespace agvslam::dynamic
