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
      yuyv[y * bpl + 2 * x + 1] = 200;                           // U or V
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

// MJPEG through libv4lconvert without a device, on a real KITTI image encoded as a UVC camera would (3-channel
// JPEG of the grey values).
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/test_data.h"

TEST(MjpegDecoder, DecodesARealFrameWithinJpegLoss) {
  AGVSLAM_REQUIRE_SHARED(path, "data/kitti06_f000-050/image_l/000000.png");
  const cv::Mat full = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(full.empty());
  const cv::Mat grey = full(cv::Rect(0, 0, full.cols & ~15, full.rows & ~15)).clone();
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}));
  v4l2::MjpegDecoder dec;
  cv::Mat out(grey.size(), CV_8UC1);
  ASSERT_TRUE(dec.decode(jpeg.data(), jpeg.size(), out)) << dec.error();
  const double mean_abs = cv::norm(out, grey, cv::NORM_L1) / static_cast<double>(grey.total());
  EXPECT_LT(mean_abs, 2.0);
  // A different frame is far off: the check the VM case relies on can tell frames apart.
  const cv::Mat other = cv::imread(path.substr(0, path.size() - 10) + "000005.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(other.empty());
  EXPECT_GT(cv::norm(out, other(cv::Rect(0, 0, out.cols, out.rows)), cv::NORM_L1) / static_cast<double>(grey.total()),
            10.0);
  // Garbage is refused with a message, not a crash.
  std::vector<uint8_t> broken(jpeg.begin(), jpeg.begin() + 200);
  EXPECT_FALSE(dec.decode(broken.data(), broken.size(), out));
  EXPECT_FALSE(dec.error().empty());
  // A size libv4lconvert cannot decode is refused too.
  cv::Mat odd(grey.rows, grey.cols - 2, CV_8UC1);
  EXPECT_FALSE(dec.decode(jpeg.data(), jpeg.size(), odd));
}
