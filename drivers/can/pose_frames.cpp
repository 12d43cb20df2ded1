#include "agvslam/drivers/can/pose_frames.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace agvslam::drivers::can {
namespace {

constexpr double kRadToDeg = 180.0 / EIGEN_PI;

// CRC-8/SAE-J1850 table for polynomial 0x1D (MSB first).
constexpr std::array<uint8_t, 256> make_crc_table() {
  std::array<uint8_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned c = i;
    for (int b = 0; b < 8; ++b) c = (c & 0x80U) != 0 ? ((c << 1) ^ 0x1DU) & 0xFFU : (c << 1) & 0xFFU;
    t[i] = static_cast<uint8_t>(c);
  }
  return t;
}
constexpr std::array<uint8_t, 256> kCrcTable = make_crc_table();

// Rounds value/step to the nearest integer and clamps it to [lo, hi] (NaN -> 0).
int64_t quantize(double value, double step, int64_t lo, int64_t hi) {
  const double q = value / step;
  if (std::isnan(q)) return 0;
  if (q <= static_cast<double>(lo)) return lo;
  if (q >= static_cast<double>(hi)) return hi;
  return std::clamp<int64_t>(std::llround(q), lo, hi);
}

uint64_t to_raw(int64_t v, unsigned length) {
  const uint64_t mask = length >= 64 ? ~0ULL : ((1ULL << length) - 1);
  return static_cast<uint64_t>(v) & mask;
}

struct Fields {
  int64_t x_mm, y_mm, z_mm, roll_cdeg, pitch_cdeg, yaw_cdeg;
  int64_t vx_mmps, vy_mmps, yaw_rate_cdegps;
  int64_t sx_mm, sy_mm, syaw_cdeg;
  int64_t latency_100us, fps_half_hz, dynamic_half_pct, dropped;
  int64_t state;
};

double stddev(double variance) { return variance > 0.0 ? std::sqrt(variance) : 0.0; }

Fields quantize_sample(const PoseSample& s) {
  constexpr int64_t i32lo = std::numeric_limits<int32_t>::min(), i32hi = std::numeric_limits<int32_t>::max();
  constexpr int64_t i16lo = std::numeric_limits<int16_t>::min(), i16hi = std::numeric_limits<int16_t>::max();
  const Eigen::Vector3d& t = s.T_map_base.translation();
  const Eigen::Matrix3d& R = s.T_map_base.linear();
  // ZYX Euler angles (yaw about z, then pitch about y, then roll about x).
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  Fields f{};
  f.x_mm = quantize(t.x(), 1e-3, i32lo, i32hi);
  f.y_mm = quantize(t.y(), 1e-3, i32lo, i32hi);
  f.z_mm = quantize(t.z(), 1e-3, i32lo, i32hi);
  f.roll_cdeg = quantize(roll * kRadToDeg, 0.01, i16lo, i16hi);
  f.pitch_cdeg = quantize(pitch * kRadToDeg, 0.01, i16lo, i16hi);
  f.yaw_cdeg = quantize(yaw * kRadToDeg, 0.01, i16lo, i16hi);
  if (f.yaw_cdeg == -18000) f.yaw_cdeg = 18000;  // (-180, 180]
  f.vx_mmps = quantize(s.v_base_mps.x(), 1e-3, i16lo, i16hi);
  f.vy_mmps = quantize(s.v_base_mps.y(), 1e-3, i16lo, i16hi);
  f.yaw_rate_cdegps = quantize(s.w_base_radps.z() * kRadToDeg, 0.01, i16lo, i16hi);
  f.sx_mm = quantize(stddev(s.cov_pose(0, 0)), 1e-3, 0, 65535);
  f.sy_mm = quantize(stddev(s.cov_pose(1, 1)), 1e-3, 0, 65535);
  f.syaw_cdeg = quantize(stddev(s.cov_pose(5, 5)) * kRadToDeg, 0.01, 0, 65535);
  f.latency_100us = quantize(static_cast<double>(s.latency_ns) * 1e-6, 0.1, 0, 65535);
  f.fps_half_hz = quantize(static_cast<double>(s.fps), 0.5, 0, 255);
  f.dynamic_half_pct = quantize(static_cast<double>(s.dynamic_pixel_fraction) * 100.0, 0.5, 0, 255);
  f.dropped = static_cast<int64_t>(s.frames_dropped & 0xFFFFU);  // wraps: a receiver looks at differences
  f.state = static_cast<int64_t>(s.tracking_state) & 0xF;
  return f;
}

CanFrameBytes classic(uint32_t offset, const FrameLayout& layout) {
  CanFrameBytes f;
  f.id = layout.base_id + offset;
  f.extended = layout.extended_ids;
  f.len = 8;
  return f;
}

void seal_classic(CanFrameBytes& f, uint8_t counter) {
  put_bits_le(f.data.data(), 52, 4, counter & 0xFU);
  f.data[7] = frame_crc(f);
}

}  // namespace

uint8_t crc8_sae_j1850(const uint8_t* data, std::size_t n, uint8_t crc) {
  for (std::size_t i = 0; i < n; ++i) crc = kCrcTable[crc ^ data[i]];
  return crc;
}

uint8_t frame_crc(const CanFrameBytes& f) {
  const uint8_t id_bytes[4] = {static_cast<uint8_t>(f.id), static_cast<uint8_t>(f.id >> 8),
                               static_cast<uint8_t>(f.id >> 16), static_cast<uint8_t>(f.id >> 24)};
  uint8_t crc = crc8_sae_j1850(id_bytes, 4, 0xFF);
  crc = crc8_sae_j1850(f.data.data(), f.len > 0 ? f.len - 1U : 0U, crc);
  return static_cast<uint8_t>(crc ^ 0xFFU);
}

void put_bits_le(uint8_t* data, unsigned start_bit, unsigned length, uint64_t raw) {
  if (start_bit % 8 == 0 && length % 8 == 0) {  // whole bytes (most signals): no bit loop
    for (unsigned b = 0; b < length / 8; ++b) data[start_bit / 8 + b] = static_cast<uint8_t>(raw >> (8 * b));
    return;
  }
  for (unsigned i = 0; i < length; ++i) {
    const unsigned bit = start_bit + i;
    const auto mask = static_cast<uint8_t>(1U << (bit % 8));
    if (((raw >> i) & 1U) != 0) {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] | mask);
    } else {
      data[bit / 8] = static_cast<uint8_t>(data[bit / 8] & ~mask);
    }
  }
}

uint64_t get_bits_le(const uint8_t* data, unsigned start_bit, unsigned length) {
  uint64_t raw = 0;
  if (start_bit % 8 == 0 && length % 8 == 0) {
    for (unsigned b = 0; b < length / 8; ++b) raw |= static_cast<uint64_t>(data[start_bit / 8 + b]) << (8 * b);
    return raw;
  }
  for (unsigned i = 0; i < length; ++i) {
    const unsigned bit = start_bit + i;
    raw |= static_cast<uint64_t>((data[bit / 8] >> (bit % 8)) & 1U) << i;
  }
  return raw;
}

std::size_t encode_classic_frames(const PoseSample& s, uint8_t counter, const FrameLayout& layout, bool with_velocity,
                                  bool with_stddev, bool with_status,
                                  std::array<CanFrameBytes, kMaxClassicFrames>& out) {
  const Fields q = quantize_sample(s);
  std::size_t n = 0;

  CanFrameBytes& a = out[n++] = classic(kPoseXYawOffset, layout);
  put_bits_le(a.data.data(), 0, 32, to_raw(q.x_mm, 32));
  put_bits_le(a.data.data(), 32, 16, to_raw(q.yaw_cdeg, 16));
  put_bits_le(a.data.data(), 48, 4, to_raw(q.state, 4));
  seal_classic(a, counter);

  CanFrameBytes& b = out[n++] = classic(kPoseYZOffset, layout);
  put_bits_le(b.data.data(), 0, 32, to_raw(q.y_mm, 32));
  put_bits_le(b.data.data(), 32, 16, to_raw(std::clamp<int64_t>(q.z_mm, -32768, 32767), 16));
  put_bits_le(b.data.data(), 48, 4, s.map_id & 0xFU);
  seal_classic(b, counter);

  if (with_velocity) {
    CanFrameBytes& v = out[n++] = classic(kVelocityOffset, layout);
    put_bits_le(v.data.data(), 0, 16, to_raw(q.vx_mmps, 16));
    put_bits_le(v.data.data(), 16, 16, to_raw(q.vy_mmps, 16));
    put_bits_le(v.data.data(), 32, 16, to_raw(q.yaw_rate_cdegps, 16));
    seal_classic(v, counter);
  }
  if (with_stddev) {
    CanFrameBytes& d = out[n++] = classic(kStdDevOffset, layout);
    put_bits_le(d.data.data(), 0, 16, to_raw(q.sx_mm, 16));
    put_bits_le(d.data.data(), 16, 16, to_raw(q.sy_mm, 16));
    put_bits_le(d.data.data(), 32, 16, to_raw(q.syaw_cdeg, 16));
    seal_classic(d, counter);
  }
  if (with_status) {
    CanFrameBytes& st = out[n++] = classic(kStatusOffset, layout);
    put_bits_le(st.data.data(), 0, 16, to_raw(q.latency_100us, 16));
    put_bits_le(st.data.data(), 16, 8, to_raw(q.fps_half_hz, 8));
    put_bits_le(st.data.data(), 24, 8, to_raw(q.dynamic_half_pct, 8));
    put_bits_le(st.data.data(), 32, 16, to_raw(q.dropped, 16));
    put_bits_le(st.data.data(), 48, 4, to_raw(q.state, 4));
    seal_classic(st, counter);
  }
  return n;
}

CanFrameBytes encode_odometry_check_frame(const OdometryCheck& check, uint8_t counter, const FrameLayout& layout) {
  constexpr int64_t kRatioNotAvailable = 0xFFFF;
  CanFrameBytes f = classic(kOdometryCheckOffset, layout);
  const int64_t ratio = std::isfinite(check.distance_ratio)
                            ? quantize(check.distance_ratio, 1e-3, 0, kRatioNotAvailable - 1)
                            : kRatioNotAvailable;
  put_bits_le(f.data.data(), 0, 16, to_raw(ratio, 16));
  put_bits_le(f.data.data(), 16, 16, to_raw(quantize(check.speed_rmse_mps, 1e-3, 0, 65535), 16));
  put_bits_le(f.data.data(), 32, 16,
              to_raw(quantize(check.heading_difference_deg, 0.01, std::numeric_limits<int16_t>::min(),
                              std::numeric_limits<int16_t>::max()),
                     16));
  put_bits_le(f.data.data(), 48, 4, to_raw(static_cast<int64_t>(check.state) & 0xF, 4));
  seal_classic(f, counter);
  return f;
}

CanFrameBytes encode_fd_frame(const PoseSample& s, uint8_t counter, const FrameLayout& layout) {
  const Fields q = quantize_sample(s);
  CanFrameBytes f;
  f.id = layout.base_id + kPoseFdOffset;
  f.extended = layout.extended_ids;
  f.fd = true;
  f.len = static_cast<uint8_t>(kPoseFdLength);
  uint8_t* d = f.data.data();
  put_bits_le(d, 0, 32, to_raw(q.x_mm, 32));
  put_bits_le(d, 32, 32, to_raw(q.y_mm, 32));
  put_bits_le(d, 64, 32, to_raw(q.z_mm, 32));
  put_bits_le(d, 96, 16, to_raw(q.roll_cdeg, 16));
  put_bits_le(d, 112, 16, to_raw(q.pitch_cdeg, 16));
  put_bits_le(d, 128, 16, to_raw(q.yaw_cdeg, 16));
  put_bits_le(d, 144, 16, to_raw(q.vx_mmps, 16));
  put_bits_le(d, 160, 16, to_raw(q.vy_mmps, 16));
  put_bits_le(d, 176, 16, to_raw(q.yaw_rate_cdegps, 16));
  put_bits_le(d, 192, 16, to_raw(q.sx_mm, 16));
  put_bits_le(d, 208, 16, to_raw(q.sy_mm, 16));
  put_bits_le(d, 224, 16, to_raw(q.syaw_cdeg, 16));
  put_bits_le(d, 240, 16, to_raw(q.latency_100us, 16));
  put_bits_le(d, 256, 8, to_raw(q.fps_half_hz, 8));
  put_bits_le(d, 264, 8, to_raw(q.dynamic_half_pct, 8));
  put_bits_le(d, 272, 16, to_raw(q.dropped, 16));
  // Capture time, milliseconds since the UNIX epoch modulo 2^32 (wraps every 49.7 days).
  const int64_t t_ms = s.t_ns >= 0 ? s.t_ns / 1000000 : -((-s.t_ns + 999999) / 1000000);
  put_bits_le(d, 288, 32, static_cast<uint64_t>(t_ms) & 0xFFFFFFFFULL);
  put_bits_le(d, 320, 32, s.frame_index & 0xFFFFFFFFULL);
  put_bits_le(d, 352, 4, to_raw(q.state, 4));
  put_bits_le(d, 356, 4, counter & 0xFU);
  put_bits_le(d, 360, 16, s.map_id & 0xFFFFU);
  f.data[kPoseFdLength - 1] = frame_crc(f);
  return f;
}

}  // namespace agvslam::drivers::can
