#include "agvslam/drivers/can/can_socket.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

namespace agvslam::drivers::can {
namespace {

std::string errno_message(const std::string& interface, const char* call, int err) {
  return interface + ": " + call + ": " + std::strerror(err);
}

}  // namespace

CanSocket::CanSocket(CanSocket&& other) noexcept : fd_(other.fd_), fd_frames_(other.fd_frames_) { other.fd_ = -1; }

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = other.fd_;
    fd_frames_ = other.fd_frames_;
    other.fd_ = -1;
  }
  return *this;
}

void CanSocket::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool CanSocket::open(const std::string& interface, bool fd_frames, std::string* error) {
  close();
  auto fail = [&](const char* call, int err) {
    if (error != nullptr) *error = errno_message(interface, call, err);
    close();
    return false;
  };
  const int s = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (s < 0) return fail("socket(PF_CAN, SOCK_RAW, CAN_RAW)", errno);
  fd_ = s;
  fd_frames_ = fd_frames;

  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) return fail("SIOCGIFINDEX (no such interface?)", errno);
  const int ifindex = ifr.ifr_ifindex;
  if (::ioctl(fd_, SIOCGIFFLAGS, &ifr) < 0) return fail("SIOCGIFFLAGS", errno);
  if ((ifr.ifr_flags & IFF_UP) == 0) return fail("interface state", ENETDOWN);

  // No data frames in (we only send), every error class in.
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0) < 0) return fail("setsockopt(CAN_RAW_FILTER)", errno);
  const can_err_mask_t err_mask = CAN_ERR_MASK;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) < 0) {
    return fail("setsockopt(CAN_RAW_ERR_FILTER)", errno);
  }
  if (fd_frames) {
    const int on = 1;
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0) {
      return fail("setsockopt(CAN_RAW_FD_FRAMES)", errno);
    }
    std::strncpy(ifr.ifr_name, interface.c_str(), IFNAMSIZ - 1);
    if (::ioctl(fd_, SIOCGIFMTU, &ifr) < 0) return fail("SIOCGIFMTU", errno);
    if (ifr.ifr_mtu != static_cast<int>(CANFD_MTU)) {
      if (error != nullptr) *error = interface + ": not a CAN FD interface (MTU " + std::to_string(ifr.ifr_mtu) + ", expected 72)";
      close();
      return false;
    }
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) return fail("bind", errno);
  return true;
}

SendResult CanSocket::send(const CanFrameBytes& f, int* err) {
  if (fd_ < 0) {
    if (err != nullptr) *err = EBADF;
    return SendResult::kDown;
  }
  canfd_frame frame{};
  frame.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0U);
  frame.len = f.len;
  std::memcpy(frame.data, f.data.data(), f.len);
  std::size_t size = CAN_MTU;
  if (f.fd) {
    frame.flags = CANFD_BRS;
    size = CANFD_MTU;
  }
  const ssize_t n = ::send(fd_, &frame, size, MSG_DONTWAIT);
  if (n == static_cast<ssize_t>(size)) return SendResult::kSent;
  const int e = n < 0 ? errno : EIO;
  if (err != nullptr) *err = e;
  switch (e) {
    case EAGAIN:
    case ENOBUFS:
      return SendResult::kNoBuffer;
    case ENETDOWN:
    case ENXIO:
    case ENODEV:
    case EBADF:
    case ENETUNREACH:
    case EADDRNOTAVAIL:
      return SendResult::kDown;
    default:
      return SendResult::kError;
  }
}

bool CanSocket::drain_error_frames(ErrorFrameCounts& counts) {
  bool bus_off = false;
  if (fd_ < 0) return false;
  for (;;) {
    canfd_frame frame{};
    const ssize_t n = ::recv(fd_, &frame, sizeof frame, MSG_DONTWAIT);
    if (n <= 0) break;
    if ((frame.can_id & CAN_ERR_FLAG) == 0) continue;
    ++counts.total;
    const canid_t cls = frame.can_id & CAN_ERR_MASK;
    bool known = false;
    if ((cls & CAN_ERR_BUSOFF) != 0) {
      ++counts.bus_off;
      bus_off = true;
      known = true;
    }
    if ((cls & CAN_ERR_CRTL) != 0) {
      ++counts.controller;
      known = true;
    }
    if ((cls & CAN_ERR_RESTARTED) != 0) {
      ++counts.restarted;
      known = true;
    }
    if ((cls & CAN_ERR_ACK) != 0) {
      ++counts.no_ack;
      known = true;
    }
    if ((cls & CAN_ERR_TX_TIMEOUT) != 0) {
      ++counts.tx_timeout;
      known = true;
    }
    if (!known) ++counts.other;
  }
  return bus_off;
}

}  // namespace agvslam::drivers::can
