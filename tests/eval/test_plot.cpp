#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/eval/plot.h"

namespace agvslam::eval {
namespace {

int count_colour(const cv::Mat& img, const cv::Vec3b& bgr, int tol) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      if (std::abs(p[0] - bgr[0]) <= tol && std::abs(p[1] - bgr[1]) <= tol && std::abs(p[2] - bgr[2]) <= tol) ++n;
    }
  return n;
}

TEST(Plot, DrawsBothTrajectoriesInTheFloorPlane) {
  // A 10 m x 6 m rectangle in the x-z plane (y is the small "up" axis), estimate offset by 0.5 m.
  std::vector<Eigen::Vector3d> gt, est;
  for (int i = 0; i < 320; ++i) {
    const double s = i / 10.0;
    Eigen::Vector3d p;
    if (s < 10)
      p = {s, 0, 0};
    else if (s < 16)
      p = {10, 0, s - 10};
    else if (s < 26)
      p = {26 - s, 0, 6};
    else
      p = {0, 0, 32 - s};
    p.y() = 0.01 * std::sin(s);
    gt.push_back(p);
    est.push_back(p + Eigen::Vector3d(0.5, 0, 0.5));
  }
  PlotOptions o;
  o.title = "test";
  const cv::Mat img = plot_top_view(gt, est, o);
  ASSERT_EQ(img.type(), CV_8UC3);
  EXPECT_EQ(img.cols, o.width_px);
  EXPECT_EQ(img.rows, o.height_px);
  // The estimate is drawn in red, ground truth in dark grey: both cover a long outline.
  EXPECT_GT(count_colour(img, {30, 60, 220}, 40), 1500);
  EXPECT_GT(count_colour(img, {40, 40, 40}, 25), 1500);
  // The rectangle is wider (x: 10 m) than tall (z: 6 m) in the picture: red pixels span more columns than rows.
  cv::Mat red;
  cv::inRange(img, cv::Scalar(0, 20, 180), cv::Scalar(80, 110, 255), red);
  const cv::Rect box = cv::boundingRect(red);
  EXPECT_GT(box.width, box.height);
}

TEST(Plot, EmptyInputStillGivesAnImage) {
  const cv::Mat img = plot_top_view({}, {}, PlotOptions{});
  EXPECT_FALSE(img.empty());
}

}  // namespace
}  // namespace agvslam::eval
