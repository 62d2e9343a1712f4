// Estimates sent as UDP datagrams, for a controller that is another
// process or on another machine (`gtrack track --stream-udp HOST:PORT`):
// one datagram a frame, its estimates.jsonl line. Sending never waits and
// never stops the run: a datagram that cannot go (the socket's buffer full,
// the network down) is dropped and counted, as UDP does on a network; one
// sent while nobody listens is lost, and a controller started late takes
// the datagrams from then on.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

class GTRACK_API UdpSender {
 public:
  // `address`: "HOST:PORT" (a name or an IPv4 address) or "[IPv6]:PORT"
  // (a link-local one with its interface, "[fe80::1%eth0]:PORT"). A name
  // with both kinds of address is sent to on its IPv4 one.
  // InputError naming `what` (e.g. "--stream-udp") and the address when it
  // is malformed, does not resolve, or no socket can be made for it.
  UdpSender(const std::string& address, const std::string& what);
  ~UdpSender();
  UdpSender(const UdpSender&) = delete;
  UdpSender& operator=(const UdpSender&) = delete;

  // Sends `datagram` without waiting; false when it was dropped. The first
  // drop of each kind is warned about, naming its cause.
  bool send(std::string_view datagram);

  long long sent() const { return sent_; }
  long long dropped() const { return dropped_; }
  // The address as resolved ("127.0.0.1:5005", "[::1]:5005", "[fe80::1%eth0]:5005").
  const std::string& peer() const { return peer_; }

 private:
  int fd_ = -1;
  alignas(8) unsigned char to_[128] = {};  // the peer's sockaddr
  unsigned to_length_ = 0;
  std::string what_, peer_;
  long long sent_ = 0, dropped_ = 0;
  std::vector<int> warned_;  // the causes (errno) of drops warned about
};

}  // namespace gtrack
