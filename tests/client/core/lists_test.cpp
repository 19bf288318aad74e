// The client's paged lists against a stand-in for canemud that answers with pages made up for
// the test: a list whose generation changes between two pages is read again from its start
// (client/src/lists.cpp, one_generation), and one that never holds still ends in an error.
#include <gtest/gtest.h>

#include <poll.h>
#include <sys/socket.h>

#include <atomic>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "../../support/temp_dir.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/seqpacket.hpp"

namespace canemu::client {
namespace {

// Answers one connection: Hello with HelloReply, every other request with what `answer` makes of
// it (the request's packet and how many requests came before it, Hello not counted).
class StandIn {
 public:
  using Answer = std::function<std::vector<uint8_t>(const std::vector<uint8_t>& request, int n)>;

  explicit StandIn(Answer answer) : answer_(std::move(answer)) {
    auto fd = ipc::listen_seqpacket(path());
    EXPECT_TRUE(fd) << (fd ? "" : fd.error().message);
    listener_ = std::move(*fd);
    thread_ = std::thread([this] { serve(); });
  }
  ~StandIn() {
    stop_ = true;
    thread_.join();
  }
  std::string path() const { return (dir_.path / "canemud.sock").string(); }
  int requests() const { return requests_; }

 private:
  void serve() {
    pollfd p{listener_.get(), POLLIN, 0};
    while (!stop_ && ::poll(&p, 1, 50) == 0) {
    }
    if (stop_) {
      return;
    }
    ipc::UniqueFd conn(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC));
    std::vector<uint8_t> packet;
    while (!stop_) {
      auto n = ipc::receive_packet(conn.get(), packet, 50);
      if (!n) {
        if (n.error().error_number == ETIMEDOUT) {
          continue;
        }
        return;
      }
      if (*n == 0) {
        return;  // the client closed
      }
      ipc::MsgHeader h;
      std::memcpy(&h, packet.data(), sizeof h);
      if (h.type == static_cast<uint16_t>(ipc::MsgType::hello)) {
        (void)ipc::send_message(conn.get(), ipc::make_message<ipc::HelloReply>(h.request_id));
        continue;
      }
      std::vector<uint8_t> reply = answer_(packet, requests_++);
      ipc::MsgHeader rh;
      std::memcpy(&rh, reply.data(), sizeof rh);
      rh.request_id = h.request_id;
      std::memcpy(reply.data(), &rh, sizeof rh);
      (void)ipc::send_packet(conn.get(), reply.data(), reply.size());
    }
  }

  testing::TempDir dir_;
  Answer answer_;
  ipc::UniqueFd listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> requests_{0};
};

template <class T>
std::vector<uint8_t> bytes_of(const T& m) {
  std::vector<uint8_t> out(sizeof m);
  std::memcpy(out.data(), &m, sizeof m);
  return out;
}

template <class T>
T request_of(const std::vector<uint8_t>& packet) {
  T m;
  std::memcpy(&m, packet.data(), sizeof m);
  return m;
}

// A fault list of `total` faults, each named "g<generation>-<index>" (its scenario), the page
// that begins at `first`.
std::vector<uint8_t> fault_page(uint16_t first, uint16_t total, uint32_t generation) {
  auto r = std::make_unique<ipc::FaultListReply>(ipc::make_message<ipc::FaultListReply>(0));
  r->total = total;
  r->first = first;
  r->generation = generation;
  for (uint16_t k = first; k < total && r->count < ipc::kFaultPage; ++k) {
    ipc::copy_name(r->faults[r->count++].scenario,
                   "g" + std::to_string(generation) + "-" + std::to_string(k));
  }
  return bytes_of(*r);
}

constexpr uint16_t kFaults = ipc::kFaultPage + 12;  // two pages

TEST(PagedLists, AFaultListThatChangesBetweenPagesIsReadAgainFromItsStart) {
  // The first reading meets generation 1 on its first page and 2 on its second (a clear moved
  // the faults); the second reading is all of generation 2.
  StandIn canemud([](const std::vector<uint8_t>& packet, int n) {
    const auto req = request_of<ipc::FaultListRequest>(packet);
    return fault_page(req.first, kFaults, n == 0 ? 1 : 2);
  });
  auto c = Connection::open(canemud.path(), "lists_test");
  ASSERT_TRUE(c) << c.error().message;
  const auto listed = fetch_fault_list(*c);
  ASSERT_TRUE(listed) << listed.error().message;
  ASSERT_EQ(listed->size(), kFaults);
  for (uint16_t k = 0; k < kFaults; ++k) {
    EXPECT_EQ(ipc::name_of((*listed)[k].scenario), "g2-" + std::to_string(k));
  }
  EXPECT_EQ(canemud.requests(), 4);  // two pages, then two more
}

TEST(PagedLists, AFaultListThatNeverHoldsStillEndsInAnError) {
  StandIn canemud([](const std::vector<uint8_t>& packet, int n) {
    const auto req = request_of<ipc::FaultListRequest>(packet);
    return fault_page(req.first, kFaults, static_cast<uint32_t>(n));  // a new one every page
  });
  auto c = Connection::open(canemud.path(), "lists_test");
  ASSERT_TRUE(c) << c.error().message;
  const auto listed = fetch_fault_list(*c);
  ASSERT_FALSE(listed);
  EXPECT_EQ(listed.error().message, "the fault list kept changing while it was read; try again");
  EXPECT_EQ(canemud.requests(), 16);  // eight readings of two pages
}

TEST(PagedLists, ADeviceListThatChangesBetweenPagesIsReadAgainWithItsGeneration) {
  constexpr uint16_t kDevices = ipc::kDevicePage + 3;
  StandIn canemud([](const std::vector<uint8_t>& packet, int n) {
    const auto req = request_of<ipc::DeviceListRequest>(packet);
    const uint32_t generation = n == 0 ? 7 : 8;
    auto r = std::make_unique<ipc::DeviceListReply>(ipc::make_message<ipc::DeviceListReply>(0));
    r->total = kDevices;
    r->first = req.first;
    r->generation = generation;
    for (uint16_t k = req.first; k < kDevices && r->count < ipc::kDevicePage; ++k) {
      ipc::copy_name(r->devices[r->count++].name,
                     "d" + std::to_string(generation) + "-" + std::to_string(k));
    }
    return bytes_of(*r);
  });
  auto c = Connection::open(canemud.path(), "lists_test");
  ASSERT_TRUE(c) << c.error().message;
  const auto listed = fetch_device_list(*c);
  ASSERT_TRUE(listed) << listed.error().message;
  EXPECT_EQ(listed->generation, 8u);
  ASSERT_EQ(listed->devices.size(), kDevices);
  for (uint16_t k = 0; k < kDevices; ++k) {
    EXPECT_EQ(ipc::name_of(listed->devices[k].name), "d8-" + std::to_string(k));
  }
}

}  // namespace
}  // namespace canemu::client
