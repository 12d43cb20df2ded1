// ObjectConfirmer on its own: objects are reported once the previous frame confirms them, large and near moving
// ones at once.
#include <gtest/gtest.h>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/object_confirmer.h"

namespace agvslam::dynamic {
namespace {

// A mask holding instance k at boxes[k - 1].
DynamicMask mask_of(const std::vector<cv::Rect>& boxes) {
  DynamicMask m;
  m.instances = cv::Mat::zeros(480, 640, CV_8UC1);
  for (std::size_t k = 0; k < boxes.size(); ++k) m.instances(boxes[k]).setTo(static_cast<int>(k + 1));
  cv::compare(m.instances, 0, m.image, cv::CMP_GT);
  m.regions = boxes;
  return m;
}

TEST(ObjectConfirmer, AnObjectWaitsForTheNextFrame) {
  ObjectConfirmer confirmer;
  DynamicMask first = mask_of({cv::Rect(100, 100, 80, 100)});
  EXPECT_EQ(confirmer.confirm(first, 0, {}), 1);
  EXPECT_EQ(first.pixel_count(), 0);
  EXPECT_TRUE(first.regions.empty());
  // Moved a little: its box overlaps the last one.
  DynamicMask second = mask_of({cv::Rect(106, 102, 80, 100)});
  EXPECT_EQ(confirmer.confirm(second, 0, {}), 0);
  EXPECT_EQ(second.pixel_count(), 80 * 100);
  // Elsewhere: it waits again.
  DynamicMask third = mask_of({cv::Rect(400, 100, 80, 100)});
  EXPECT_EQ(confirmer.confirm(third, 0, {}), 1);
  confirmer.reset();
  DynamicMask after_reset = mask_of({cv::Rect(400, 100, 80, 100)});
  EXPECT_EQ(confirmer.confirm(after_reset, 0, {}), 1);
}

TEST(ObjectConfirmer, LargeAndNearMovingObjectsAreReportedAtOnce) {
  ObjectConfirmer confirmer;
  DynamicMask large = mask_of({cv::Rect(100, 100, 200, 200)});  // 40000 px >= confirm.below_px
  EXPECT_EQ(confirmer.confirm(large, 0, {}), 0);
  EXPECT_EQ(large.pixel_count(), 40000);
  ObjectConfirmer fresh;
  // Instances 1 and 2 are near and moving (1500 px >= near_min_px each), but 2 lies inside instance 3's box (a
  // fragment of it); 3 (10500 px) is neither large nor near: 2 and 3 wait.
  DynamicMask near = mask_of({cv::Rect(20, 20, 30, 50), cv::Rect(300, 100, 30, 50), cv::Rect(250, 80, 100, 120)});
  near.instances(cv::Rect(300, 100, 30, 50)).setTo(2);
  EXPECT_EQ(fresh.confirm(near, 0, {0, 1, 1, 0}), 2);
  EXPECT_EQ(cv::countNonZero(near.instances == 1), 1500);
  EXPECT_EQ(cv::countNonZero(near.instances), 1500);
  EXPECT_EQ(near.regions, (std::vector<cv::Rect>{cv::Rect(20, 20, 30, 50)}));
  ObjectConfirmer off(ConfirmOptions{0.0});
  DynamicMask any = mask_of({cv::Rect(100, 100, 10, 10)});
  EXPECT_EQ(off.confirm(any, 0, {}), 0);
}

TEST(ObjectConfirmer, NearMovingNeedsDisparityOffsetAndFill) {
  const ConfirmOptions o;
  EXPECT_TRUE(o.near_moving(15, 4, 600, 1000));
  EXPECT_FALSE(o.near_moving(10, 4, 600, 1000));  // too far
  EXPECT_FALSE(o.near_moving(15, 2, 600, 1000));  // too little off the ego-motion
  EXPECT_FALSE(o.near_moving(15, 4, 300, 1000));  // a partial outline
  ConfirmOptions off;
  off.near_min_px = 0;
  EXPECT_FALSE(off.near_moving(15, 4, 600, 1000));
}

TEST(ObjectConfirmer, AFragmentLiesHalfInsideAnotherObjectsBox) {
  // An arm outlined apart from its person is not reported at once.
  const std::vector<cv::Rect> boxes = {cv::Rect(),                   // instance 0: none
                                       cv::Rect(0, 0, 276, 428),     // a person
                                       cv::Rect(101, 282, 52, 99),   // an arm inside its box
                                       cv::Rect(250, 100, 52, 100),  // half of it inside (26 of 52 columns)
                                       cv::Rect(251, 0, 52, 90),     // just under half inside (25 columns)
                                       cv::Rect(400, 0, 100, 300)};  // a person apart
  EXPECT_FALSE(lies_half_inside_another(boxes, 1));  // the arm inside it does not make the person a fragment
  EXPECT_TRUE(lies_half_inside_another(boxes, 2));
  EXPECT_TRUE(lies_half_inside_another(boxes, 3));
  EXPECT_FALSE(lies_half_inside_another(boxes, 4));
  EXPECT_FALSE(lies_half_inside_another(boxes, 5));
  EXPECT_FALSE(lies_half_inside_another({cv::Rect(0, 0, 10, 10)}, 0));
}

TEST(ObjectConfirmer, OptionsAreValidatedUnderTheirSection) {
  ConfirmOptions o;
  EXPECT_NO_THROW(o.validate("test"));
  o.min_box_iou = 1.5;
  try {
    o.validate("test");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "confirm.min_box_iou");
  }
}

}  // namespace
}  // namespace agvslam::dynamic
