#include "agvslam/eval/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"

namespace agvslam::eval {
namespace {

const cv::Scalar kWhite(255, 255, 255), kBlack(0, 0, 0), kGrid(225, 225, 225), kAxis(90, 90, 90);
const cv::Scalar kGtColour(40, 40, 40), kEstColour(30, 60, 220);  // BGR: dark grey, red

// 1, 2 or 5 times a power of ten, giving about `target` intervals over span.
double nice_step(double span, int target) {
  const double raw = span / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10.0 * mag;
}

std::string format_number(double v, double step) {
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

void put_text(cv::Mat& img, const std::string& text, cv::Point org, double scale, const cv::Scalar& colour,
              int thickness = 1) {
  cv::putText(img, text, org, cv::FONT_HERSHEY_SIMPLEX, scale, colour, thickness, cv::LINE_AA);
}

}  // namespace

cv::Mat plot_top_view(const std::vector<Eigen::Vector3d>& p_gt, const std::vector<Eigen::Vector3d>& p_est,
                      const PlotOptions& options) {
  const std::vector<Eigen::Vector3d>& ref = p_gt.empty() ? p_est : p_gt;
  cv::Mat img(options.height_px, options.width_px, CV_8UC3, kWhite);
  if (ref.empty()) {
    put_text(img, "no poses to plot", {40, 60}, 0.8, kBlack);
    return img;
  }

  // The plane: the two axes along which the reference spreads most, in axis order.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : ref) mean += p;
  mean /= static_cast<double>(ref.size());
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (const auto& p : ref) var += (p - mean).cwiseAbs2();
  int drop = 0;
  var.minCoeff(&drop);
  std::array<int, 2> axes{};
  for (int a = 0, k = 0; a < 3; ++a)
    if (a != drop) axes[static_cast<std::size_t>(k++)] = a;
  const char* names = "xyz";

  double min_u = 1e300, max_u = -1e300, min_v = 1e300, max_v = -1e300;
  for (const auto* list : {&p_gt, &p_est})
    for (const auto& p : *list) {
      min_u = std::min(min_u, p[axes[0]]);
      max_u = std::max(max_u, p[axes[0]]);
      min_v = std::min(min_v, p[axes[1]]);
      max_v = std::max(max_v, p[axes[1]]);
    }
  const double span = std::max({max_u - min_u, max_v - min_v, 0.1});
  const double pad = 0.08 * span;
  min_u -= pad, max_u += pad, min_v -= pad, max_v += pad;

  const int left = 90, right = 30, top = 60, bottom = 70;
  const int plot_w = options.width_px - left - right, plot_h = options.height_px - top - bottom;
  const double px_per_m = std::min(plot_w / (max_u - min_u), plot_h / (max_v - min_v));
  const double cu = 0.5 * (min_u + max_u), cv_ = 0.5 * (min_v + max_v);
  const double u0 = cu - 0.5 * plot_w / px_per_m, u1 = cu + 0.5 * plot_w / px_per_m;
  const double v0 = cv_ - 0.5 * plot_h / px_per_m, v1 = cv_ + 0.5 * plot_h / px_per_m;
  auto to_px = [&](double u, double v) {
    return cv::Point(static_cast<int>(std::lround(left + (u - u0) * px_per_m)),
                     static_cast<int>(std::lround(top + (v1 - v) * px_per_m)));
  };

  // Grid, ticks and labels.
  const double step = nice_step(std::max(u1 - u0, v1 - v0), 8);
  for (double u = std::ceil(u0 / step) * step; u <= u1; u += step) {
    const int x = to_px(u, v0).x;
    cv::line(img, {x, top}, {x, top + plot_h}, kGrid, 1);
    put_text(img, format_number(u, step), {x - 14, top + plot_h + 20}, 0.45, kAxis);
  }
  for (double v = std::ceil(v0 / step) * step; v <= v1; v += step) {
    const int y = to_px(u0, v).y;
    cv::line(img, {left, y}, {left + plot_w, y}, kGrid, 1);
    put_text(img, format_number(v, step), {left - 60, y + 5}, 0.45, kAxis);
  }
  cv::rectangle(img, {left, top}, {left + plot_w, top + plot_h}, kAxis, 1);
  put_text(img, std::string(1, names[axes[0]]) + " [m]", {left + plot_w / 2 - 20, options.height_px - 25}, 0.6, kBlack);
  put_text(img, std::string(1, names[axes[1]]) + " [m]", {10, top - 15}, 0.6, kBlack);

  auto draw_path = [&](const std::vector<Eigen::Vector3d>& pts, const cv::Scalar& colour, int thickness) {
    if (pts.empty()) return;
    std::vector<cv::Point> poly;
    poly.reserve(pts.size());
    for (const auto& p : pts) poly.push_back(to_px(p[axes[0]], p[axes[1]]));
    cv::polylines(img, poly, false, colour, thickness, cv::LINE_AA);
    cv::circle(img, poly.front(), 6, colour, 2, cv::LINE_AA);                                     // start
    cv::rectangle(img, poly.back() - cv::Point(5, 5), poly.back() + cv::Point(5, 5), colour, 2);  // end
  };
  draw_path(p_gt, kGtColour, 2);
  draw_path(p_est, kEstColour, 2);

  // Legend.
  int ly = top + 20;
  const int lx = left + 15;
  cv::rectangle(img, {lx - 8, ly - 16}, {lx + 300, ly + (p_est.empty() || p_gt.empty() ? 14 : 40)}, kWhite, cv::FILLED);
  cv::rectangle(img, {lx - 8, ly - 16}, {lx + 300, ly + (p_est.empty() || p_gt.empty() ? 14 : 40)}, kAxis, 1);
  for (const auto& [pts, colour, label] :
       {std::tuple{&p_gt, kGtColour, options.gt_label}, std::tuple{&p_est, kEstColour, options.est_label}}) {
    if (pts->empty()) continue;
    cv::line(img, {lx, ly - 4}, {lx + 30, ly - 4}, colour, 2, cv::LINE_AA);
    put_text(img, label, {lx + 40, ly}, 0.5, kBlack);
    ly += 26;
  }
  put_text(img, "o start   [] end", {left + plot_w - 160, top + plot_h - 10}, 0.45, kAxis);

  // Scale bar (one grid step) under the plot on the right.
  const int bar_px = static_cast<int>(std::lround(step * px_per_m));
  const cv::Point bar_end(left + plot_w, options.height_px - 30);
  cv::line(img, bar_end - cv::Point(bar_px, 0), bar_end, kBlack, 3);
  put_text(img, format_number(step, step) + " m", bar_end - cv::Point(bar_px / 2 + 20, 10), 0.5, kBlack);

  if (!options.title.empty()) put_text(img, options.title, {left, 35}, 0.65, kBlack, 1);
  return img;
}

void save_top_view(const std::string& path, const std::vector<Eigen::Vector3d>& p_gt,
                   const std::vector<Eigen::Vector3d>& p_est, const PlotOptions& options) {
  const cv::Mat img = plot_top_view(p_gt, p_est, options);
  bool ok = false;
  try {
    ok = cv::imwrite(path, img);
  } catch (const cv::Exception& e) {
    throw InputError(path, "plot", std::string("could not write the PNG: ") + e.what());
  }
  if (!ok)
    throw InputError(path, "plot",
                     "could not write the PNG (is the folder there and writable, and does the name end in .png?)");
}

}  // namespace agvslam::eval
