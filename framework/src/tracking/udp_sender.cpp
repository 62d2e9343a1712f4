// UDP datagrams to a controller (see udp_sender.hpp).
#include "gtrack/udp_sender.hpp"

#include <arpa/inet.h>
#include <net/if.h>
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"

namespace gtrack {

UdpSender::UdpSender(const std::string& address, const std::string& what) : what_(what) {
  const auto refuse = [&](const std::string& why) {
    throw InputError(what + " '" + address + "': " + why);
  };
  // HOST:PORT, the host in brackets when it is an IPv6 address.
  std::string host, port;
  if (!address.empty() && address.front() == '[') {
    const auto close = address.find(']');
    if (close == std::string::npos || close + 1 >= address.size() || address[close + 1] != ':') {
      refuse("expected [IPv6]:PORT, e.g. [::1]:5005");
    }
    host = address.substr(1, close - 1);
    port = address.substr(close + 2);
  } else {
    const auto colon = address.rfind(':');
    if (colon == std::string::npos || address.find(':') != colon) {
      refuse("expected HOST:PORT, e.g. 127.0.0.1:5005 (an IPv6 address in brackets: [::1]:5005)");
    }
    host = address.substr(0, colon);
    port = address.substr(colon + 1);
  }
  int number = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), number);
  if (host.empty() || port.empty() || ec != std::errc() || end != port.data() + port.size() || number < 1 ||
      number > 65535) {
    refuse("expected HOST:PORT with a host and a port from 1 to 65535");
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  // An address as written; else a name, resolved to the families this
  // machine has an address of.
  hints.ai_flags = AI_NUMERICSERV | AI_NUMERICHOST;
  addrinfo* found = nullptr;
  int r = ::getaddrinfo(host.c_str(), port.c_str(), &hints, &found);
  if (r == EAI_NONAME) {
    hints.ai_flags = AI_NUMERICSERV | AI_ADDRCONFIG;
    r = ::getaddrinfo(host.c_str(), port.c_str(), &hints, &found);
  }
  if (r != 0) refuse(std::string("cannot resolve the host (") + ::gai_strerror(r) + ")");
  // A name with both: its IPv4 address, which a controller bound to
  // 0.0.0.0 (the usual) hears; "localhost" is often ::1 first.
  std::vector<addrinfo*> order;
  for (addrinfo* a = found; a; a = a->ai_next) {
    if (a->ai_family == AF_INET) order.push_back(a);
  }
  for (addrinfo* a = found; a; a = a->ai_next) {
    if (a->ai_family != AF_INET) order.push_back(a);
  }
  std::string why = "no address";
  static_assert(sizeof(to_) >= sizeof(sockaddr_in6));
  for (addrinfo* a : order) {
    if (a->ai_family == AF_INET6) {
      // A link-local address means nothing without its interface.
      const auto* v6 = reinterpret_cast<const sockaddr_in6*>(a->ai_addr);
      if (IN6_IS_ADDR_LINKLOCAL(&v6->sin6_addr) && v6->sin6_scope_id == 0) {
        ::freeaddrinfo(found);
        refuse("a link-local address needs its interface; expected [fe80::...%IFACE]:PORT, e.g. [fe80::1%eth0]:5005");
      }
    }
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      why = std::strerror(errno);
      continue;
    }
    if (a->ai_addrlen > sizeof to_) {
      ::close(fd);
      continue;
    }
    // Not connected: a peer with nobody listening (ICMP port unreachable)
    // does not turn later sends into errors; a controller started late
    // takes the datagrams from then on. A subnet's broadcast address
    // (192.168.1.255) is taken as any other.
    const int yes = 1;
    if (a->ai_family == AF_INET) ::setsockopt(fd, SOL_SOCKET, SO_BROADCAST, &yes, sizeof yes);
    std::memcpy(to_, a->ai_addr, a->ai_addrlen);
    to_length_ = a->ai_addrlen;
    char text[INET6_ADDRSTRLEN] = {};
    const bool v6 = a->ai_family == AF_INET6;
    const void* ip = v6 ? static_cast<const void*>(&reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_addr)
                        : static_cast<const void*>(&reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr);
    ::inet_ntop(a->ai_family, ip, text, sizeof text);
    std::string shown = text;
    if (v6) {
      char name[IF_NAMESIZE] = {};
      const unsigned scope = reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_scope_id;
      if (scope != 0) shown += "%" + std::string(::if_indextoname(scope, name) ? name : std::to_string(scope).c_str());
      shown = "[" + shown + "]";
    }
    peer_ = shown + ":" + std::to_string(number);
    fd_ = fd;
    break;
  }
  ::freeaddrinfo(found);
  if (fd_ < 0) refuse("cannot make a socket for it (" + why + ")");
  logger().info("{}: each estimate goes to {} as a UDP datagram", what_, peer_);
}

UdpSender::~UdpSender() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpSender::send(std::string_view datagram) {
  for (;;) {
    if (::sendto(fd_, datagram.data(), datagram.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                 reinterpret_cast<const sockaddr*>(to_), to_length_) >= 0) {
      ++sent_;
      return true;
    }
    if (errno != EINTR) break;
  }
  const int error = errno;
  ++dropped_;
  if (std::find(warned_.begin(), warned_.end(), error) == warned_.end()) {
    warned_.push_back(error);
    const char* cause = error == EAGAIN || error == EWOULDBLOCK ? "the socket's buffer is full"
                        : error == EMSGSIZE                        ? "the datagram is too large"
                                                                   : "the network refused it";
    logger().warn("{} {}: a datagram was dropped: {} ({}); the run goes on, and later drops for this cause are "
                  "counted, not said",
                  what_, peer_, cause, std::strerror(error));
  }
  return false;
}

}  // namespace gtrack
