#include "dynamic_overlay.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "agvslam/core/error.h"

namespace agvslam::apps::dynamic_tool {

namespace dyn = agvslam::dynamic;

std::string frame_name(std::size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06zu.png", i);
  return buf;
}

void write_png(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
  } catch (const cv::Exception& e) {
    throw InputError("--out", path, std::string("could not write the image: ") + e.what());
  }
  if (!ok) throw InputError("--out", path, "could not write the image (disk full or not writable?)");
}

namespace {

cv::Mat grey_to_bgr(const cv::Mat& grey) {
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

void label(cv::Mat& panel, const std::string& text) {
  cv::rectangle(panel, cv::Rect(0, 0, panel.cols, 26), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(panel, text, cv::Point(8, 19), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

cv::Mat disparity_panel(const cv::Mat& disparity_px, double max_disparity_px) {
  cv::Mat scaled, colour;
  disparity_px.convertTo(scaled, CV_8U, 255.0 / std::max(1.0, max_disparity_px));
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  colour.setTo(cv::Scalar(0, 0, 0), disparity_px <= 0);
  return colour;
}

cv::Mat points_panel(const cv::Mat& left, const dyn::DetectorResult& r) {
  cv::Mat panel = grey_to_bgr(left);
  for (const auto& roi : r.rois) cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 2);
  for (const auto& p : r.points) {
    if (!p.tracked) continue;
    cv::Scalar colour =
        p.dynamic ? (p.densified ? cv::Scalar(0, 140, 255) : cv::Scalar(0, 0, 255)) : cv::Scalar(0, 200, 0);
    cv::line(panel, p.prev_px, p.cur_px, colour, 1, cv::LINE_AA);
    cv::circle(panel, p.cur_px, p.dynamic ? 3 : 2, colour, p.dynamic ? cv::FILLED : 1, cv::LINE_AA);
  }
  // The left band's seeds (cyan, band_segmenter.h) and the outlines of its regions (magenta).
  for (const auto& region : r.band.regions) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(region.mask.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE, region.rect.tl());
    cv::drawContours(panel, contours, -1, cv::Scalar(255, 0, 255), 1);
  }
  for (const auto& seed : r.band.seeds) {
    cv::line(panel, seed.prev_px, seed.cur_px, cv::Scalar(255, 255, 0), 1, cv::LINE_AA);
    cv::circle(panel, seed.cur_px, 3, cv::Scalar(255, 255, 0), cv::FILLED, cv::LINE_AA);
  }
  return panel;
}

cv::Mat superpixel_panel(const cv::Mat& left, const dyn::DetectorResult& r) {
  cv::Mat panel = grey_to_bgr(left);
  for (const auto& roi : r.rois) {
    if (roi.labels.empty() && !roi.outline.empty()) {
      // mask_mode disparity: the ROI's disparity (grey: none) with the object's outline in red.
      const cv::Rect area = roi.roi & cv::Rect(cv::Point(0, 0), panel.size());
      cv::Mat disp = disparity_panel(roi.disparity_px, std::max(8.0, 2.0 * roi.mean_disparity_px));
      disp.setTo(cv::Scalar(90, 90, 90), roi.disparity_px <= 0);
      cv::addWeighted(panel(area), 0.4, disp(cv::Rect(area.tl() - roi.roi.tl(), area.size())), 0.6, 0, panel(area));
      // Red: a dynamic region; orange: an outline the checks dropped (its verdict is written above the ROI).
      const bool kept = roi.outline_verdict == dyn::OutlineVerdict::kKept;
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(roi.outline.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE, roi.roi.tl());
      cv::drawContours(panel, contours, -1, kept ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 140, 255), 1);
      if (!kept) {
        cv::putText(panel, dyn::to_string(roi.outline_verdict), roi.roi.tl() + cv::Point(2, -4),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 140, 255), 1, cv::LINE_AA);
      }
      for (int k : roi.points)
        cv::circle(panel, r.points[static_cast<std::size_t>(k)].cur_px, 2, cv::Scalar(255, 255, 255), cv::FILLED);
      cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 1);
      continue;
    }
    if (roi.labels.empty()) continue;
    std::map<std::pair<int, int>, dyn::BoundaryType> types;
    for (const auto& b : roi.boundaries) types[{b.i, b.j}] = b.type;
    auto colour_of = [&](int a, int b) {
      const auto it = types.find({std::min(a, b), std::max(a, b)});
      const dyn::BoundaryType t = it == types.end() ? dyn::BoundaryType::kUnknown : it->second;
      if (dyn::is_occlusion(t)) return cv::Vec3b(0, 0, 255);
      if (t == dyn::BoundaryType::kHinge) return cv::Vec3b(255, 120, 0);
      if (t == dyn::BoundaryType::kCoplanar) return cv::Vec3b(255, 255, 255);
      return cv::Vec3b(160, 160, 160);
    };
    const cv::Mat& labels = roi.labels;
    // Photometric check: green tint = moves with the background, magenta = moved differently.
    if (!roi.motion.empty()) {
      for (int y = 0; y < labels.rows; ++y) {
        const int* row = labels.ptr<int>(y);
        for (int x = 0; x < labels.cols; ++x) {
          const int k = row[x];
          if (k < 0 || static_cast<std::size_t>(k) >= roi.motion.size() ||
              roi.motion[static_cast<std::size_t>(k)].apparent_motion_px < 0)
            continue;
          const cv::Point p(roi.roi.x + x, roi.roi.y + y);
          if (p.x >= panel.cols || p.y >= panel.rows) continue;
          cv::Vec3b& px = panel.at<cv::Vec3b>(p);
          const cv::Vec3b tint = roi.motion[static_cast<std::size_t>(k)].moves_with_background ? cv::Vec3b(0, 255, 0)
                                                                                               : cv::Vec3b(255, 0, 255);
          for (int c = 0; c < 3; ++c) px[c] = static_cast<uint8_t>((px[c] * 2 + tint[c]) / 3);
        }
      }
    }
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      const int* below = y + 1 < labels.rows ? labels.ptr<int>(y + 1) : nullptr;
      for (int x = 0; x < labels.cols; ++x) {
        int other = -1;
        if (x + 1 < labels.cols && row[x + 1] != row[x])
          other = row[x + 1];
        else if (below && below[x] != row[x])
          other = below[x];
        if (other < 0) continue;
        const cv::Point p(roi.roi.x + x, roi.roi.y + y);
        if (p.x < panel.cols && p.y < panel.rows) panel.at<cv::Vec3b>(p) = colour_of(row[x], other);
      }
    }
    cv::rectangle(panel, roi.roi, cv::Scalar(0, 220, 255), 1);
  }
  return panel;
}

cv::Mat regions_panel(const cv::Mat& left, const dyn::DetectorResult& r, const cv::Mat& gt_mask) {
  cv::Mat panel = grey_to_bgr(left);
  auto tint = [&](const cv::Mat& where, const cv::Scalar& colour) {
    cv::Mat solid(panel.size(), CV_8UC3, colour), blended;
    cv::addWeighted(panel, 0.45, solid, 0.55, 0, blended);
    blended.copyTo(panel, where);
  };
  if (gt_mask.empty()) {
    tint(r.mask.image, cv::Scalar(0, 0, 255));
  } else {  // green: detected and moving; red: detected but static; blue: moving but missed
    tint(r.mask.image & gt_mask, cv::Scalar(0, 200, 0));
    tint(r.mask.image & ~gt_mask, cv::Scalar(0, 0, 255));
    tint(~r.mask.image & gt_mask, cv::Scalar(255, 0, 0));
  }
  for (const auto& rect : r.mask.regions) cv::rectangle(panel, rect, cv::Scalar(0, 0, 255), 1);
  return panel;
}

}  // namespace

cv::Mat compose_overlay(const cv::Mat& left, const cv::Mat& right, const dyn::DetectorResult& r, const cv::Mat& gt_mask,
                        agvslam::stereo::StereoSgbm& sgbm) {
  cv::Mat disparity_px;
  sgbm.compute(left, right, disparity_px);
  cv::Mat a = disparity_panel(disparity_px, sgbm.config().max_disparity());
  cv::Mat b = points_panel(left, r);
  cv::Mat c = superpixel_panel(left, r);
  cv::Mat d = regions_panel(left, r, gt_mask);
  label(a, "(a) SGBM disparity (whole frame, for display)");
  label(b, "(b) tracks: green static, red dynamic; yellow: dynamic ROIs");
  label(c, r.rois.empty() || !r.rois.front().labels.empty()
               ? "(c) red occlusion, blue hinge; tint: green static, magenta moved"
               : "(c) ROI disparity; outline: red region, orange dropped");
  label(d, gt_mask.empty() ? "(d) dynamic mask and regions (red)" : "(d) mask: green correct, red false, blue missed");
  cv::Mat top, bottom, all;
  cv::hconcat(a, b, top);
  cv::hconcat(c, d, bottom);
  cv::vconcat(top, bottom, all);
  return all;
}

}  // namespace agvslam::apps::dynamic_tool
