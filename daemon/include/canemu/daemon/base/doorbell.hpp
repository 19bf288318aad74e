// What the server's event loop wakes when a client rings: a channel whose transmit ring got
// elements while the daemon slept on it. Ephemeral channels (channel.hpp) and VCI channels
// (vci_port.hpp) are both.
#pragma once

#include <cstdint>

namespace canemu::daemon {

class Doorbell {
 public:
  // Readable when the client put elements while the daemon slept.
  virtual int doorbell_fd() const = 0;
  // The doorbell rang (or the loop wants idle transmitters to look again).
  virtual void kick() = 0;
  // When the client rang it, as the client's CLOCK_MONOTONIC in ns, taken once (0: not known):
  // in real and scaled time the loop kicks the doorbell at that instant of simulated time, as
  // if it had been awake when the client queued its frame (docs/daemon.md, "Pacing").
  virtual int64_t take_rung_ns() { return 0; }
  // The kick at that instant. True: all of it (the loop does not kick it again at "now"); false:
  // only what belongs to that instant, the rest at "now" (Distributed: the requests alone).
  virtual bool kick_rung() {
    kick();
    return true;
  }
  // The client broke a ring; the server drops the client.
  virtual bool broken() const = 0;
  // Whether a transmitter that empties its ring arms the doorbell (the default). Not in stepped
  // time, where the loop looks at every ring when a step begins (Server::kick_all_channels)
  // and a doorbell would only wake it for nothing: an arm costs a system-wide memory barrier.
  virtual void set_arming(bool arming) { (void)arming; }

 protected:
  ~Doorbell() = default;
};

// Who watches doorbells (the server's loop): told of each one as it comes and before it goes.
class DoorbellWatch {
 public:
  virtual void watch(Doorbell& bell) = 0;
  virtual void unwatch(Doorbell& bell) = 0;

 protected:
  ~DoorbellWatch() = default;
};

}  // namespace canemu::daemon
