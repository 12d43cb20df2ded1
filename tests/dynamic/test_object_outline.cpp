// ObjectOutliner on constructed disparity images: the object is exactly the pixels connected to its points
// through smooth disparity, without the floor it stands on, with its textureless holes and the plain surfaces
// between it and the floor, and split from a surface at its depth by static points when static competition is on.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/object_outline.h"
#include "noise_texture.h"

namespace agvslam::dynamic {
namespace {

constexpr double kBf = 55.2;  // 460 px * 0.12 m
constexpr double kCy = 40.0;  // horizon row of the ROI

// A 160 x 120 ROI at (100, 50) of the image: a wall at d = 4, optionally a floor d = 0.25 (y - 100) (image rows)
// where that exceeds 4 (ROI rows >= 67), and a "person" (ROI x 60..79, y 20..89) at d = 10: the floor reaches
// d = 10 at ROI row 90, right under the feet.
struct Scene {
  cv::Point origin{100, 50};
  cv::Mat disparity = cv::Mat(120, 160, CV_32FC1, cv::Scalar(4.0f));
  DisparityPlane ground;
  cv::Rect person{60, 20, 20, 70};

  explicit Scene(bool with_floor = true) {
    ground.a = 0;
    ground.b = 0.25;
    ground.c = -0.25 * 100;  // d = 0.25 (y_image - 100)
    ground.valid = with_floor;
    for (int y = 0; with_floor && y < disparity.rows; ++y) {
      const double d_floor = ground.disparity_at(0, y + origin.y);
      if (d_floor > 4.0) disparity.row(y).setTo(static_cast<float>(d_floor));
    }
    disparity(person).setTo(10.0f);
  }
  cv::Point2f image_point(int x, int y) const {
    return {static_cast<float>(x + origin.x), static_cast<float>(y + origin.y)};
  }
};

// The flood itself: no erosion (tested separately).
OutlineConfig exact() {
  OutlineConfig c;
  c.erode_px = 0;
  return c;
}

cv::Mat expected_mask(const Scene& s, const cv::Rect& object) {
  cv::Mat m(s.disparity.size(), CV_8UC1, cv::Scalar(0));
  m(object).setTo(255);
  return m;
}

TEST(ObjectOutline, PersonOnTheFloorIsExactlyItsPixels) {
  Scene s;
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  const std::vector<cv::Point2f> points = {s.image_point(65, 30), s.image_point(72, 60), s.image_point(70, 85)};
  const std::vector<float> d = {10.0f, 10.2f, 9.9f};
  const OutlineStats st = outliner.outline(s.disparity, s.origin, points, d, {}, {}, &s.ground, kBf, mask);
  EXPECT_EQ(st.object_seeds, 3);
  // The feet touch the floor (ROI row 89 is the person's last, the floor has d = 10 at row 90): the floor stays
  // out, and so do the soles, rows 87..89, whose d = 10 is within 0.6 + 0.03 d of the floor's 9.25..9.75 there.
  const cv::Rect above_floor(s.person.x, s.person.y, s.person.width, 67);
  EXPECT_EQ(cv::countNonZero(mask != expected_mask(s, above_floor)), 0);
  EXPECT_EQ(st.object_pixels, above_floor.area());
}

TEST(ObjectOutline, WithoutTheGroundPlaneTheFloorLeaksIn) {
  Scene s;
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  outliner.outline(s.disparity, s.origin, {s.image_point(70, 60)}, {10.0f}, {}, {}, nullptr, kBf, mask);
  // The floor rows next to the feet have d = 10 +- a few 0.25 px steps: connected, within the depth band.
  EXPECT_GT(cv::countNonZero(mask), s.person.area() + 100);
}

TEST(ObjectOutline, TexturelessHolesJoinAndEnclosedBackgroundDoesNot) {
  Scene s;
  // No disparity inside the shirt (textureless), and a gap between the legs showing the wall (valid d = 4).
  s.disparity(cv::Rect(63, 30, 14, 20)).setTo(0.0f);
  s.disparity(cv::Rect(68, 70, 4, 20)).setTo(4.0f);
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  outliner.outline(s.disparity, s.origin, {s.image_point(61, 25), s.image_point(61, 80)}, {10.0f, 10.0f}, {}, {},
                   &s.ground, kBf, mask);
  cv::Mat expected = expected_mask(s, cv::Rect(s.person.x, s.person.y, s.person.width, 67));  // soles: floor
  expected(cv::Rect(68, 70, 4, 20)).setTo(0);  // the gap opens onto the floor below: background
  EXPECT_EQ(cv::countNonZero(mask != expected), 0);
}

// A vehicle seen from behind (ROI x 30..109, rows 10..89, d = 10, standing on the floor row 90): a textured cab on
// top and a plain counterweight below, where SGBM (no texture to match) returns rows of the background's d = 4,
// holes and the right d by turns, from side to side; only the 3 rows under the cab and above the floor, matched on
// those edges, are right.
struct Vehicle {
  Scene s;
  cv::Rect body{30, 10, 80, 80};
  cv::Rect plain{30, 43, 80, 44};  // the counterweight between those rows
  cv::Mat left = test::noise_texture(160, 120, 7);

  Vehicle() {
    s.disparity(body).setTo(10.0f);
    for (int y = plain.y; y < plain.br().y; ++y) {
      const float garbage[3] = {4.0f, 0.0f, 10.0f};
      s.disparity(cv::Rect(plain.x, y, plain.width, 1)).setTo(garbage[((y - plain.y) / 3) % 3]);
    }
    left(cv::Rect(body.x, 40, body.width, 50)).setTo(90);
  }
  // Its dynamic points: corners of the cab only (the counterweight has none).
  std::vector<cv::Point2f> points() const {
    return {s.image_point(40, 20), s.image_point(70, 25), s.image_point(100, 30)};
  }
};

TEST(ObjectOutline, APlainCounterweightJoinsDownToTheFloor) {
  Vehicle v;
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  const std::vector<float> d(3, 10.0f);
  outliner.outline(v.s.disparity, v.s.origin, v.points(), d, {}, {}, &v.s.ground, kBf, mask);
  // The flood alone stops at the first row of background disparity under the cab.
  EXPECT_LT(cv::countNonZero(mask(v.plain)), v.plain.area() / 4);
  outliner.outline(v.s.disparity, v.s.origin, v.points(), d, {}, {}, &v.s.ground, kBf, mask, v.left);
  // With the image, the counterweight (unmeasured) joins but for the few columns at its sides and rows at its
  // bottom that are matched on the wall's and the floor's texture (with its garbage disparity); nothing beside or
  // under the vehicle joins.
  EXPECT_GT(cv::countNonZero(mask(v.body)), v.body.area() * 9 / 10);
  cv::Mat outside = mask.clone();
  outside(v.body).setTo(0);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  // Without a floor there is nothing to reach: only rows between two outline pixels may join.
  outliner.outline(v.s.disparity, v.s.origin, v.points(), d, {}, {}, nullptr, kBf, mask, v.left);
  EXPECT_LT(cv::countNonZero(mask(v.plain)), v.plain.area() / 2);
}

TEST(ObjectOutline, MeasuredBackgroundBetweenTheLegsStaysOut) {
  Scene s;
  // Textured everywhere but the shirt; a gap between the legs showing the (textured) wall at d = 4.
  cv::Mat left = test::noise_texture(160, 120, 11);
  left(cv::Rect(63, 30, 14, 20)).setTo(120);
  s.disparity(cv::Rect(63, 30, 14, 20)).setTo(0.0f);
  s.disparity(cv::Rect(68, 70, 4, 20)).setTo(4.0f);
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  outliner.outline(s.disparity, s.origin, {s.image_point(61, 25), s.image_point(61, 80)}, {10.0f, 10.0f}, {}, {},
                   &s.ground, kBf, mask, left);
  cv::Mat expected = expected_mask(s, cv::Rect(s.person.x, s.person.y, s.person.width, 67));
  expected(cv::Rect(68, 70, 4, 20)).setTo(0);
  EXPECT_EQ(cv::countNonZero(mask != expected), 0);
}

TEST(ObjectOutline, SeedsNeedAgreeingDisparityAndTheDepthBandCutsSlopes) {
  Scene s(false);
  ObjectOutliner outliner(exact());
  cv::Mat mask;
  // A point whose disparity matches nothing within seed_radius_px starts nothing.
  OutlineStats st =
      outliner.outline(s.disparity, s.origin, {s.image_point(70, 60)}, {14.0f}, {}, {}, nullptr, kBf, mask);
  EXPECT_EQ(st.object_seeds, 0);
  EXPECT_EQ(cv::countNonZero(mask), 0);
  // A ramp of disparity 10 -> 20 across the person's width in 0.5 px steps (smooth): only the part within
  // depth_band_m of the seed's depth joins.
  for (int x = 0; x < s.person.width; ++x)
    s.disparity(cv::Rect(s.person.x + x, s.person.y, 1, s.person.height)).setTo(10.0f + 0.5f * x);
  OutlineConfig c = exact();
  c.depth_band_m = 0.6;
  ObjectOutliner narrow(c);
  st = narrow.outline(s.disparity, s.origin, {s.image_point(60, 50)}, {10.0f}, {}, {}, nullptr, kBf, mask);
  EXPECT_EQ(st.object_seeds, 1);
  // z(seed) = 5.52 m; the band reaches z = 4.92 m, d = 11.22: columns with 10 + 0.5 x <= 11.22, x <= 2.
  EXPECT_EQ(cv::countNonZero(mask), 3 * s.person.height);
}

TEST(ObjectOutline, StaticPointsClaimASurfaceAtTheObjectsDepth) {
  Scene s(false);
  // A shelf at the person's depth right beside it (x 80..119), joined without a disparity step.
  s.disparity(cv::Rect(80, 20, 40, 70)).setTo(10.0f);
  OutlineConfig c = exact();
  c.static_competition = true;
  ObjectOutliner outliner(c);
  cv::Mat mask;
  outliner.outline(s.disparity, s.origin, {s.image_point(62, 50), s.image_point(66, 60)}, {10.0f, 10.0f},
                   {s.image_point(110, 50), s.image_point(116, 60)}, {10.0f, 10.0f}, nullptr, kBf, mask);
  // Each pixel goes to the nearer seed (4-connected distance): the boundary falls between x = 66 and 110,
  // so the person (x < 80) is entirely in, and most of the shelf is out.
  EXPECT_EQ(cv::countNonZero(mask(s.person)), s.person.area());
  EXPECT_LT(cv::countNonZero(mask(cv::Rect(90, 20, 30, 70))), 30 * 70 / 10);
  c.static_competition = false;
  ObjectOutliner greedy(c);
  greedy.outline(s.disparity, s.origin, {s.image_point(62, 50)}, {10.0f}, {s.image_point(110, 50)}, {10.0f}, nullptr,
                 kBf, mask);
  EXPECT_EQ(cv::countNonZero(mask(cv::Rect(80, 20, 40, 70))), 40 * 70);
}

TEST(ObjectOutline, ErosionTakesTheSgbmFatteningOff) {
  Scene s(false);
  OutlineConfig c = exact();
  c.erode_px = 1;
  ObjectOutliner outliner(c);
  cv::Mat mask;
  outliner.outline(s.disparity, s.origin, {s.image_point(70, 50)}, {10.0f}, {}, {}, nullptr, kBf, mask);
  const cv::Rect inner(s.person.x + 1, s.person.y + 1, s.person.width - 2, s.person.height - 2);
  EXPECT_EQ(cv::countNonZero(mask != expected_mask(s, inner)), 0);
}

TEST(ObjectOutline, TracksMovingTogetherBelowTheirOwnThresholds) {
  OutlineConfig c;
  c.aggregate_ratio = 3.0;
  c.aggregate_min_px = 0.45;
  // A person walking ahead: the median offset of its tracks is 0.94 px (each below a per-track threshold of ~2 px
  // at d = 30); the frame's static tracks are at 0.15 px.
  EXPECT_TRUE(tracks_move_together(0.94, 0.15, c));
  // The same offsets in a frame whose static tracks are at 0.4 px (vibration): 3 x 0.4 = 1.2 px > 0.94.
  EXPECT_FALSE(tracks_move_together(0.94, 0.4, c));
  // A static surface flooded from a depth edge keeps the static offsets.
  EXPECT_FALSE(tracks_move_together(0.14, 0.15, c));
  // Absolute floor: in a perfectly still frame (static median 0) a median offset under aggregate_min_px is noise.
  EXPECT_FALSE(tracks_move_together(0.3, 0.0, c));
  EXPECT_TRUE(tracks_move_together(0.45, 0.0, c));
  EXPECT_FALSE(tracks_move_together(-1, 0.15, c));  // no offset measured
  c.aggregate_ratio = 0;                            // off
  EXPECT_FALSE(tracks_move_together(0.94, 0.15, c));
}

TEST(ObjectOutline, TracksMovingTogetherByTheMultiFrameTest) {
  OutlineConfig c;
  c.aggregate_min_tracks = 5;
  c.aggregate_multiframe_fraction = 0.5;
  c.aggregate_multiframe_min_px = 0.2;
  // A person walking ahead in a turn: 30 of its 41 tracks off the multi-frame reference, per-frame median 0.77 px.
  EXPECT_TRUE(tracks_move_together_multiframe(41, 30, 0.77, c));
  EXPECT_TRUE(tracks_move_together_multiframe(10, 5, 0.2, c));    // exactly half, exactly the floor
  EXPECT_FALSE(tracks_move_together_multiframe(10, 4, 0.77, c));  // fewer than half flagged
  // A person who has just stopped: still off the reference, frame to frame at the static tracks' 0.11 px.
  EXPECT_FALSE(tracks_move_together_multiframe(34, 31, 0.11, c));
  EXPECT_FALSE(tracks_move_together_multiframe(4, 4, 0.77, c));  // fewer than aggregate_min_tracks tested
  EXPECT_FALSE(tracks_move_together_multiframe(0, 0, 0.77, c));
  EXPECT_FALSE(tracks_move_together_multiframe(41, 30, -1, c));  // no per-frame offset measured
  c.aggregate_min_tracks = 0;
  EXPECT_TRUE(tracks_move_together_multiframe(2, 2, 0.5, c));
  EXPECT_FALSE(tracks_move_together_multiframe(0, 0, 0.5, c));
  c.aggregate_multiframe_fraction = 0;  // off
  EXPECT_FALSE(tracks_move_together_multiframe(41, 30, 0.77, c));
}

TEST(ObjectOutline, InvalidConfigurationNamesTheField) {
  OutlineConfig c;
  c.depth_band_m = 0;
  try {
    ObjectOutliner o(c);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "outline.depth_band_m");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
