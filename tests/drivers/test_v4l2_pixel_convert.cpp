#include <gtest/gtest.h>

#include <vector>

#include "agvslam/drivers/v4l2/pixel_convert.h"

namespace v4l2 = agvslam::drivers::v4l2;

TEST(PixelConvert, YuyvTakesLumaWithRowPadding) {
  const int w = 6, h = 3;
  const std::size_t bpl = 2 * w + 4;  // padded rows, as some drivers deliver
  std::vector<uint8_t> yuyv(bpl * h, 0xEE);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      yuyv[y * bpl + 2 * x] = static_cast<uint8_t>(10 * y + x);  // Y
      yuyv[y * bpl + 2 * x + 1] = 200;                            // U or V
    }
  cv::Mat grey(h, w, CV_8UC1);
  v4l2::yuyv_to_grey(yuyv.data(), bpl, grey);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) EXPECT_EQ(grey.at<uint8_t>(y, x), 10 * y + x);
}

TEST(PixelConvert, GreyHonoursStride) {
  const int w = 5, h = 4;
  std::vector<uint8_t> src(8 * h, 0xFF);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) src[y * 8 + x] = static_cast<uint8_t>(y * w + x);
  cv::Mat grey(h, w, CV_8UC1);
  v4l2::grey_to_grey(src.data(), 8, grey);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) EXPECT_EQ(grey.at<uint8_t>(y, x), y * w + x);
  cv::Mat same(h, w, CV_8UC1);
  v4l2::grey_to_grey(grey.data, w, same);  // unpadded fast path
  EXPECT_EQ(cv::norm(grey, same, cv::NORM_INF), 0.0);
}

TEST(PixelConvert, HashIsStrideIndependentAndSeesOnePixel) {
  cv::Mat big(40, 61, CV_8UC1);
  cv::randu(big, 0, 256);
  const cv::Mat roi = big(cv::Rect(3, 2, 51, 30));  // not continuous
  const cv::Mat copy = roi.clone();
  EXPECT_EQ(v4l2::image_hash(roi), v4l2::image_hash(copy));
  cv::Mat changed = copy.clone();
  changed.at<uint8_t>(29, 50) ^= 1;  // last pixel, in the byte-wise tail of the row
  EXPECT_NE(v4l2::image_hash(changed), v4l2::image_hash(copy));
  changed = copy.clone();
  changed.at<uint8_t>(0, 0) ^= 0x80;
  EXPECT_NE(v4l2::image_hash(changed), v4l2::image_hash(copy));
}
