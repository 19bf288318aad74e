// The LIN controller: modes, the response table, the transmit buffer, online and offline.
#include "canemu/firmware_model/chips/lin/lin_controller.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canemu::model::lin {
namespace {

struct Seen : LinController::Listener {
  void on_lin(const Event& e, bool own) override { events.push_back({e, own}); }
  std::vector<std::pair<Event, bool>> events;
};

class LinControllerTest : public ::testing::Test {
 protected:
  LinControllerTest() {
    master.set_listener(&master_seen);
    slave.set_listener(&slave_seen);
    master.configure(LinController::Mode::master, 19200);
    slave.configure(LinController::Mode::slave, 19200);
  }
  void run_to(int64_t ns) { scheduler.run_until(SimTime::from_ns(ns)); }

  SimScheduler scheduler;
  LinBus bus{scheduler, Layout{}};
  LinController master{bus};
  LinController slave{bus};
  Seen master_seen;
  Seen slave_seen;
};

Response two_bytes() {
  Response r;
  r.size = 2;
  r.data[0] = 0xAB;
  r.data[1] = 0xCD;
  return r;
}

TEST_F(LinControllerTest, TheSlavesTableAnswersTheMastersHeader) {
  slave.set_response(0x10, two_bytes());
  master.start();
  slave.start();
  EXPECT_EQ(master.send_header(0x10), LinController::SendResult::ok);
  EXPECT_TRUE(master.tx_pending());
  EXPECT_EQ(master.send_header(0x10), LinController::SendResult::busy);
  run_to(bits_duration(64, 19200).ns());
  ASSERT_EQ(slave_seen.events.size(), 1u);
  EXPECT_TRUE(slave_seen.events[0].second);  // its own response
  ASSERT_EQ(master_seen.events.size(), 1u);
  EXPECT_FALSE(master_seen.events[0].second);
  EXPECT_EQ(master_seen.events[0].first.response.data[1], 0xCD);
  EXPECT_FALSE(master.tx_pending());
}

TEST_F(LinControllerTest, WhatASlaveMayNotSendAndWhatOfflineRefuses) {
  EXPECT_EQ(master.send_header(1), LinController::SendResult::offline);
  slave.start();
  EXPECT_EQ(slave.send_header(1), LinController::SendResult::not_master);
  EXPECT_EQ(slave.send_frame(1, two_bytes()), LinController::SendResult::not_master);
  EXPECT_EQ(slave.send_sleep(), LinController::SendResult::not_master);
  EXPECT_EQ(slave.send_wakeup(), LinController::SendResult::ok);
  master.start();
  run_to(250'000);
  ASSERT_EQ(master_seen.events.size(), 1u);
  EXPECT_EQ(master_seen.events[0].first.kind, Event::Kind::wakeup);
  EXPECT_EQ(master_seen.events[0].first.at.ns(), 250'000);
}

TEST_F(LinControllerTest, AnOfflineControllerNeitherAnswersNorHears) {
  slave.set_response(0x10, two_bytes());
  master.start();
  master.send_header(0x10);
  run_to(bits_duration(160, 19200).ns());
  EXPECT_TRUE(slave_seen.events.empty());
  ASSERT_EQ(master_seen.events.size(), 1u);
  EXPECT_EQ(master_seen.events[0].first.error, ErrorKind::no_response);
}

TEST_F(LinControllerTest, ResetEmptiesTheTableAndDropsARequestNotStarted) {
  slave.set_response(0x10, two_bytes());
  slave.reset();
  EXPECT_FALSE(slave.response(0x10).has_value());
  EXPECT_FALSE(slave.online());
  master.start();
  slave.start();
  master.send_header(0x10);
  run_to(bits_duration(160, 19200).ns());
  EXPECT_EQ(master_seen.events.at(0).first.error, ErrorKind::no_response);
}

TEST_F(LinControllerTest, TheMasterAnswersItsOwnHeaderFromItsTable) {
  master.set_response(0x21, two_bytes());
  master.start();
  slave.start();
  master.send_header(0x21);
  run_to(bits_duration(64, 19200).ns());
  ASSERT_EQ(master_seen.events.size(), 1u);
  EXPECT_TRUE(master_seen.events[0].second);
  EXPECT_EQ(slave_seen.events.at(0).first.responder, master.node());
}

TEST_F(LinControllerTest, AutomaticBitRateComesFromTheFirstHeader) {
  slave.configure(LinController::Mode::slave, 0);
  EXPECT_EQ(slave.bitrate(), 0u);
  master.configure(LinController::Mode::master, 10417);
  master.start();
  slave.start();
  slave.set_response(0x01, two_bytes());
  master.send_header(0x01);
  run_to(bits_duration(64, 10417).ns());
  EXPECT_EQ(slave.bitrate(), 10417u);
  EXPECT_EQ(slave_seen.events.at(0).first.kind, Event::Kind::frame);
}

}  // namespace
}  // namespace canemu::model::lin
