#pragma once
// Per-keypoint kernels of the ORB extractor (private to the features module). Each gives exactly the result of
// OpenCV's ORB code for the same inputs (integer moments; the same float rotation and rounding of the pattern).
#include <cstdint>

namespace agvslam::features::detail {

// Intensity-centroid moments over the disc of radius 15 around `center` (umax[v]: half-width of row v, v in
// [0, 15]): m_01 = sum v I, m_10 = sum u I.
void ic_moments(const uint8_t* center, int step, const int* umax, int& m_01, int& m_10);

// 32-byte rotated BRIEF descriptor at `center` of the blurred level (a = cos, b = sin of the keypoint angle).
void orb_descriptor(const uint8_t* center, int step, float a, float b, uint8_t* descriptor);

// The plain loops (reference for the SIMD versions, used where SSE2 is missing).
void ic_moments_scalar(const uint8_t* center, int step, const int* umax, int& m_01, int& m_10);
void orb_descriptor_scalar(const uint8_t* center, int step, float a, float b, uint8_t* descriptor);

}  // namespace agvslam::features::detail
