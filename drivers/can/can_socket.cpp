#include "agvslam/drivers/can/can_socket.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <ctime>

namespace agvslam::drivers::can {
namespace {

// Fallback stamp when the kernel sent none.
int64_t realtime_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

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

bool CanSocket::open(const std::string& interface, bool fd_frames, std::string* error,
                     const std::vector<CanId>& receive) {
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

  // Data frames: only the ids asked for (none: the socket only sends); every error class in.
  std::vector<can_filter> filters;
  for (const CanId& r : receive) {
    can_filter f{};
    f.can_id = r.id | (r.extended ? CAN_EFF_FLAG : 0U);
    f.can_mask = (r.extended ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG;
    filters.push_back(f);
  }
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, filters.empty() ? nullptr : filters.data(),
                   static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
    return fail("setsockopt(CAN_RAW_FILTER)", errno);
  }
  if (!receive.empty()) {
    const int on = 1;
    if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) < 0)
      return fail("setsockopt(SO_TIMESTAMPNS)", errno);
  }
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
      if (error != nullptr)
        *error = interface + ": not a CAN FD interface (MTU " + std::to_string(ifr.ifr_mtu) + ", expected 72)";
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

bool CanSocket::drain(ErrorFrameCounts& counts, std::vector<ReceivedCanFrame>* received) {
  bool bus_off = false;
  if (fd_ < 0) return false;
  for (;;) {
    canfd_frame frame{};
    iovec iov{&frame, sizeof frame};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n <= 0) break;
    if ((frame.can_id & CAN_ERR_FLAG) == 0) {
      if (received == nullptr || (frame.can_id & CAN_RTR_FLAG) != 0) continue;
      ReceivedCanFrame r;
      r.frame.extended = (frame.can_id & CAN_EFF_FLAG) != 0;
      r.frame.id = frame.can_id & (r.frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
      r.frame.fd = n == static_cast<ssize_t>(CANFD_MTU);
      r.frame.len = std::min<uint8_t>(frame.len, r.frame.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN);
      std::memcpy(r.frame.data.data(), frame.data, r.frame.len);
      r.t_ns = realtime_ns();
      for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          r.t_ns = static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
        }
      }
      received->push_back(r);
      continue;
    }
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
