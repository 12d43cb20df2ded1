#pragma once
// FAST-9 (16-pixel circle) corner strength of every pixel (private to the features module).
//
// The strength S of a pixel is the largest t for which it is a FAST corner plus one: the maximum, over the 16
// arcs of 9 contiguous circle pixels and both polarities, of the smallest |centre - circle| difference on the
// arc (0 when no arc is all brighter or all darker). A pixel is a corner of cv::FAST at threshold t iff S > t,
// and then OpenCV's score (cornerScore, the keypoint response) is S - 1. With S of all pixels at hand, FAST at
// any threshold with non-maximum suppression is: S > t and S greater than each of its 8 neighbours' S (a
// neighbour that is no corner at t has S <= t < S of the centre, so it never suppresses, as in OpenCV).
#include <cstdint>

namespace agvslam::features::detail {

// S for pixels row[0 .. n) of a row whose circle (+-3 rows and columns) lies inside the image; `stride` is the
// row step in bytes. out[0 .. n).
void fast_strength_row(const uint8_t* row, int stride, int n, uint8_t* out);
void fast_strength_row_scalar(const uint8_t* row, int stride, int n, uint8_t* out);

// Columns x in [x0, x1) of one row of the strength map whose strength exceeds `threshold` and each of its 8
// neighbours' (the rows above and below, `step` bytes away, and columns x0 - 1 and x1 must be readable). Writes
// them to xs (room for x1 - x0 entries) in increasing order and returns their count.
int local_maxima_row(const uint8_t* row, int step, int x0, int x1, int threshold, int* xs);

}  // namespace agvslam::features::detail
