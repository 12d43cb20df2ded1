#include <gtest/gtest.h>

#include <stdexcept>

#include "agvslam/eval/object_motion.h"

namespace agvslam::eval {
namespace {

// A 752x480 camera (the simulator's: fx, fy, cx, cy, width, height), bf = 55.2 px*m.
PinholeCamera camera() { return {460, 460, 375.5, 239.5, 752, 480}; }
constexpr double kBf = 55.2;

// Object `id` as a fronto-parallel rectangle at disparity_px.
void draw(cv::Mat& instances, cv::Mat& disparity, int id, const cv::Rect& r, float disparity_px) {
  instances(r).setTo(id);
  disparity(r).setTo(disparity_px);
}

struct Pair {
  cv::Mat inst_then = cv::Mat::zeros(480, 752, CV_8UC1), inst_now = cv::Mat::zeros(480, 752, CV_8UC1);
  cv::Mat disp_then = cv::Mat::zeros(480, 752, CV_32FC1), disp_now = cv::Mat::zeros(480, 752, CV_32FC1);
};

// The camera moves 0.06 m to its right: a surface at d = 20 px (2.76 m) moves 460 * 0.06 / 2.76 = 10 px left.
SE3d camera_moves_right() {
  SE3d T_now_then = SE3d::Identity();
  T_now_then.translation() = Eigen::Vector3d(-0.06, 0, 0);
  return T_now_then;
}

TEST(ObjectMotion, AStaticObjectHasNoOffsetWhateverTheCameraDoes) {
  Pair p;
  draw(p.inst_then, p.disp_then, 3, cv::Rect(300, 150, 40, 120), 20.0f);
  draw(p.inst_now, p.disp_now, 3, cv::Rect(290, 150, 40, 120), 20.0f);
  const ObjectImageMotion m = ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(),
                                                        kBf, camera_moves_right());
  ASSERT_TRUE(m.valid);
  EXPECT_NEAR(m.offset_px, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(m.visible_ratio, 1.0);
  EXPECT_EQ(m.pixels_then, 40 * 120);
}

TEST(ObjectMotion, AMovingObjectIsOffByItsOwnMotion) {
  Pair p;
  draw(p.inst_then, p.disp_then, 3, cv::Rect(300, 150, 40, 120), 20.0f);
  // It walked 7 px right and 3 px down while the camera moved: 10 px left of where it was, plus its own motion.
  draw(p.inst_now, p.disp_now, 3, cv::Rect(297, 153, 40, 120), 20.0f);
  // Another object does not count.
  draw(p.inst_now, p.disp_now, 5, cv::Rect(500, 150, 40, 120), 10.0f);
  const ObjectImageMotion m = ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(),
                                                        kBf, camera_moves_right());
  ASSERT_TRUE(m.valid);
  EXPECT_NEAR(m.offset_px, std::hypot(7.0, 3.0), 1e-6);
}

TEST(ObjectMotion, AnObjectWhoseVisiblePartChangedIsNotMeasured) {
  Pair p;
  draw(p.inst_then, p.disp_then, 3, cv::Rect(300, 150, 40, 120), 20.0f);
  draw(p.inst_now, p.disp_now, 3, cv::Rect(290, 150, 20, 120), 20.0f);  // half of it now hidden: centroid shifts 10 px
  const ObjectImageMotion m = ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(),
                                                        kBf, camera_moves_right());
  EXPECT_FALSE(m.valid);
  EXPECT_DOUBLE_EQ(m.visible_ratio, 0.5);
  EXPECT_NEAR(m.offset_px, 10.0, 1e-6);
}

TEST(ObjectMotion, TooFewPixelsOrAMissingObjectIsNotMeasured) {
  Pair p;
  draw(p.inst_then, p.disp_then, 3, cv::Rect(300, 150, 10, 10), 20.0f);  // 100 px < 200
  draw(p.inst_now, p.disp_now, 3, cv::Rect(290, 150, 10, 10), 20.0f);
  EXPECT_FALSE(ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(), kBf,
                                         camera_moves_right())
                   .valid);
  EXPECT_FALSE(ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 4, camera(), kBf,
                                         camera_moves_right())
                   .valid);
  ObjectMotionConfig fewer;
  fewer.min_pixels = 50;
  EXPECT_TRUE(ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(), kBf,
                                        camera_moves_right(), fewer)
                  .valid);
}

TEST(ObjectMotion, PixelsWithoutDisparityAreLeftOut) {
  Pair p;
  draw(p.inst_then, p.disp_then, 3, cv::Rect(300, 150, 40, 120), 20.0f);
  draw(p.inst_now, p.disp_now, 3, cv::Rect(290, 150, 40, 120), 20.0f);
  p.disp_then(cv::Rect(300, 150, 40, 60)).setTo(0.0f);  // top half unmatched then: its centroid is the bottom half's
  p.disp_now(cv::Rect(290, 150, 40, 60)).setTo(0.0f);
  const ObjectImageMotion m = ground_truth_image_motion(p.inst_then, p.disp_then, p.inst_now, p.disp_now, 3, camera(),
                                                        kBf, camera_moves_right());
  ASSERT_TRUE(m.valid);
  EXPECT_EQ(m.pixels_then, 40 * 60);
  EXPECT_NEAR(m.offset_px, 0.0, 1e-6);
}

TEST(ObjectMotion, WrongImageTypesAreRejected) {
  Pair p;
  cv::Mat disparity_u16 = cv::Mat::zeros(480, 752, CV_16UC1);
  EXPECT_THROW(ground_truth_image_motion(p.inst_then, disparity_u16, p.inst_now, p.disp_now, 3, camera(), kBf,
                                         camera_moves_right()),
               std::invalid_argument);
}

}  // namespace
}  // namespace agvslam::eval
