// EdgeRefiner on a constructed stereo pair: a textured board at d_f in front of a textured wall at d_b. The
// outline that SGBM would give (fattened into the wall at both sides, or cut short) must come back to the board's
// true columns; where the images cannot tell (no texture, no background disparity) it must stay as it is.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/edge_refine.h"

namespace agvslam::dynamic {
namespace {

constexpr int kW = 240, kH = 140;
constexpr int kBoardX0 = 100, kBoardX1 = 140;  // board columns [x0, x1) in the left image
constexpr int kBoardY0 = 30, kBoardY1 = 110;
const cv::Rect kRoi(60, 20, 130, 100);  // where outline and disparity lie

// Smooth random texture (blurred noise), wider than the image so that shifted reads stay inside.
cv::Mat texture(unsigned seed, int width) {
  cv::Mat t(kH, width, CV_32FC1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 255.0f);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) t.at<float>(y, x) = u(rng);
  cv::GaussianBlur(t, t, cv::Size(0, 0), 0.8);
  return t;
}

struct Pair {
  cv::Mat left, right;
  float d_f, d_b;
};

// Left image: the wall shows wall(x), the board board(x). Right image column x' sees the board where x' + d_f
// falls on it, else the wall at x' + d_b (integer disparities: no resampling).
Pair make_pair(int d_f, int d_b, bool textured = true) {
  const cv::Mat wall = texture(1, kW + 64), board = texture(2, kW + 64);
  Pair p{cv::Mat(kH, kW, CV_8UC1), cv::Mat(kH, kW, CV_8UC1), static_cast<float>(d_f), static_cast<float>(d_b)};
  for (int y = 0; y < kH; ++y) {
    const bool board_row = y >= kBoardY0 && y < kBoardY1;
    for (int x = 0; x < kW; ++x) {
      const bool on_board = board_row && x >= kBoardX0 && x < kBoardX1;
      const bool right_on_board = board_row && x + d_f >= kBoardX0 && x + d_f < kBoardX1;
      const float l = on_board ? board.at<float>(y, x) : wall.at<float>(y, x);
      const float r = right_on_board ? board.at<float>(y, x + d_f) : wall.at<float>(y, x + d_b);
      p.left.at<uint8_t>(y, x) = textured ? cv::saturate_cast<uint8_t>(l) : (on_board ? 60 : 180);
      p.right.at<uint8_t>(y, x) = textured ? cv::saturate_cast<uint8_t>(r) : (right_on_board ? 60 : 180);
    }
  }
  return p;
}

// What SGBM gives: the board's disparity over [x0 - fat, x1 + fat), none in the strip left of it that the board
// hides from the right camera, the wall's elsewhere. Outline: the board's columns widened by `fat`.
void sgbm_like(const Pair& p, int fat, cv::Mat& disparity, cv::Mat& outline, bool wall_disparity = true) {
  disparity.create(kRoi.size(), CV_32FC1);
  outline.create(kRoi.size(), CV_8UC1);
  outline.setTo(0);
  const int hidden = static_cast<int>(p.d_f - p.d_b);
  for (int y = 0; y < kRoi.height; ++y) {
    const int iy = y + kRoi.y;
    for (int x = 0; x < kRoi.width; ++x) {
      const int ix = x + kRoi.x;
      const bool board = iy >= kBoardY0 && iy < kBoardY1 && ix >= kBoardX0 - fat && ix < kBoardX1 + fat;
      const bool occluded = iy >= kBoardY0 && iy < kBoardY1 && ix >= kBoardX0 - hidden && ix < kBoardX0 - fat;
      disparity.at<float>(y, x) = board ? p.d_f : (occluded || !wall_disparity) ? 0.0f : p.d_b;
      if (board) outline.at<uint8_t>(y, x) = 255;
    }
  }
}

// Per row of the board: the outline's run [first, last] in image columns. (In the two rows at the board's top
// and bottom the 1 x 5 window reaches over its edge onto the wall, and either answer may win: not checked.)
void expect_board_columns(const cv::Mat& outline, int tolerance_px, double exact_fraction) {
  int rows = 0, exact = 0;
  for (int iy = kBoardY0 + 2; iy < kBoardY1 - 2; ++iy) {
    const uint8_t* row = outline.ptr<uint8_t>(iy - kRoi.y);
    int first = -1, last = -1;
    for (int x = 0; x < outline.cols; ++x) {
      if (row[x] && first < 0) first = x;
      if (row[x]) last = x;
    }
    ASSERT_GE(first, 0) << "row " << iy;
    first += kRoi.x;
    last += kRoi.x;
    EXPECT_NEAR(first, kBoardX0, tolerance_px) << "row " << iy;
    EXPECT_NEAR(last, kBoardX1 - 1, tolerance_px) << "row " << iy;
    ++rows;
    exact += (first == kBoardX0 && last == kBoardX1 - 1) ? 1 : 0;
  }
  EXPECT_GE(exact, exact_fraction * rows);
}

EdgeRefineConfig on() {
  EdgeRefineConfig c;
  c.band_px = 6;
  return c;
}

TEST(EdgeRefine, AFattenedOutlineComesBackToTheBoardsSides) {
  const Pair p = make_pair(14, 5);
  cv::Mat disparity, outline;
  sgbm_like(p, 3, disparity, outline);
  EdgeRefiner refiner(on());
  const EdgeRefineStats st = refiner.refine(p.left, p.right, kRoi, disparity, outline);
  EXPECT_EQ(st.sides, 2 * (kBoardY1 - kBoardY0));
  EXPECT_EQ(st.pixels_added, 0);
  EXPECT_GE(st.pixels_removed, 5 * (kBoardY1 - kBoardY0));
  expect_board_columns(outline, 1, 0.9);
  // Rows above and below the board are untouched (empty).
  EXPECT_EQ(cv::countNonZero(outline.rowRange(0, kBoardY0 - kRoi.y)), 0);
}

TEST(EdgeRefine, AnOutlineCutShortGrowsBackToTheSides) {
  const Pair p = make_pair(14, 5);
  cv::Mat disparity, outline;
  sgbm_like(p, -3, disparity, outline);  // 3 px short at either side
  EdgeRefiner refiner(on());
  const EdgeRefineStats st = refiner.refine(p.left, p.right, kRoi, disparity, outline);
  EXPECT_GE(st.pixels_added, 5 * (kBoardY1 - kBoardY0));
  expect_board_columns(outline, 1, 0.9);
}

TEST(EdgeRefine, WithoutTextureOrBackgroundDisparityTheOutlineStays) {
  {
    const Pair p = make_pair(14, 5, /*textured=*/false);  // flat board on a flat wall: only the sides tell
    cv::Mat disparity, outline;
    sgbm_like(p, 0, disparity, outline);
    const cv::Mat before = outline.clone();
    EdgeRefiner refiner(on());
    refiner.refine(p.left, p.right, kRoi, disparity, outline);
    EXPECT_EQ(cv::countNonZero(outline != before), 0);
  }
  {
    const Pair p = make_pair(14, 5);
    cv::Mat disparity, outline;
    sgbm_like(p, 3, disparity, outline, /*wall_disparity=*/false);
    const cv::Mat before = outline.clone();
    EdgeRefiner refiner(on());
    const EdgeRefineStats st = refiner.refine(p.left, p.right, kRoi, disparity, outline);
    EXPECT_EQ(st.moved, 0);
    EXPECT_EQ(cv::countNonZero(outline != before), 0);
  }
  {
    // Board and wall less than min_disparity_gap_px apart: nothing to decide between.
    const Pair p = make_pair(6, 5);
    cv::Mat disparity, outline;
    sgbm_like(p, 3, disparity, outline);
    EdgeRefineConfig c = on();
    c.min_disparity_gap_px = 2.0;
    EdgeRefiner refiner(c);
    EXPECT_EQ(refiner.refine(p.left, p.right, kRoi, disparity, outline).moved, 0);
  }
}

TEST(EdgeRefine, OffLeavesTheOutlineAndBadConfigNamesTheField) {
  const Pair p = make_pair(14, 5);
  cv::Mat disparity, outline;
  sgbm_like(p, 3, disparity, outline);
  const cv::Mat before = outline.clone();
  EdgeRefineConfig off;
  off.band_px = 0;
  EdgeRefiner refiner(off);
  EXPECT_EQ(refiner.refine(p.left, p.right, kRoi, disparity, outline).sides, 0);
  EXPECT_EQ(cv::countNonZero(outline != before), 0);

  EdgeRefineConfig bad = on();
  bad.half_rows = -1;
  try {
    EdgeRefiner r(bad);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "edge_refine.half_rows");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
