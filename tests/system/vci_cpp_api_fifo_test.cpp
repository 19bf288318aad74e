// The FIFOs of the VCI C++ API (libvciapi) against a real canemud in stepped time: stand-alone
// FIFOs shared between processes, a channel's reader and writer with their events, locks,
// levels and thresholds, echoes, overrun and delayed messages.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "vci_cpp_test_support.hpp"
#include "vcisdk.h"

namespace canemu::testing {
namespace {

TEST(VciCppApi, AStandAloneFifoKeepsOrderCountsAndSignalsOnWritesOnly) {
  VciDaemon d;
  StandAloneFifo fifo(32, 16);
  Ref<IFifoReader> twice;
  EXPECT_EQ(VciAccessFifo(fifo.id, IID_IFifoReader, twice.pv()), VCI_E_ACCESSDENIED);
  UINT16 capacity = 0;
  UINT16 size = 0;
  ASSERT_EQ(fifo.reader->GetCapacity(&capacity), VCI_OK);
  ASSERT_EQ(fifo.reader->GetEntrySize(&size), VCI_OK);
  EXPECT_GE(capacity, 32);
  EXPECT_EQ(size, 16);
  const Event event;
  ASSERT_EQ(fifo.reader->SetThreshold(3), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(event), VCI_OK);
  uint8_t element[16] = {};
  for (uint8_t k = 1; k <= 5; ++k) {
    element[0] = k;
    ASSERT_EQ(fifo.writer->PutDataEntry(element), VCI_OK);
  }
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);  // the third write crossed 3
  UINT16 fill = 0;
  UINT16 free_count = 0;
  ASSERT_EQ(fifo.reader->GetFillCount(&fill), VCI_OK);
  ASSERT_EQ(fifo.reader->GetFreeCount(&free_count), VCI_OK);
  EXPECT_EQ(fill, 5);
  EXPECT_EQ(fill + free_count, capacity);
  // Acquire five, release two: the next acquire starts at the third.
  PVOID p = nullptr;
  UINT16 count = 0;
  ASSERT_EQ(fifo.reader->AcquireRead(&p, &count), VCI_OK);
  EXPECT_EQ(count, 5);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 1);
  ASSERT_EQ(fifo.reader->ReleaseRead(2), VCI_OK);
  ASSERT_EQ(fifo.reader->AcquireRead(&p, &count), VCI_OK);
  EXPECT_EQ(count, 3);
  EXPECT_EQ(static_cast<uint8_t*>(p)[0], 3);
  ASSERT_EQ(fifo.reader->ReleaseRead(0), VCI_OK);
  // Acquired without a count pointer, one element may be released.
  ASSERT_EQ(fifo.reader->AcquireRead(&p, nullptr), VCI_OK);
  EXPECT_EQ(fifo.reader->ReleaseRead(2), VCI_E_INVALIDARG);
  ASSERT_EQ(fifo.reader->ReleaseRead(1), VCI_OK);         // the third
  ASSERT_EQ(fifo.reader->GetDataEntry(nullptr), VCI_OK);  // drops the fourth
  ASSERT_EQ(fifo.reader->GetDataEntry(element), VCI_OK);
  EXPECT_EQ(element[0], 5);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);  // reads signal nothing
  // Lock is recursive.
  EXPECT_EQ(fifo.reader->Lock(), VCI_OK);
  EXPECT_EQ(fifo.reader->Lock(), VCI_OK);
  EXPECT_EQ(fifo.reader->Unlock(), VCI_OK);
  EXPECT_EQ(fifo.reader->Unlock(), VCI_OK);
  // Reset only with no reader and writer open.
  Ref<IVciFifo2> whole;
  ASSERT_EQ(VciAccessFifo(fifo.id, IID_IVciFifo2, whole.pv()), VCI_OK);
  EXPECT_EQ(whole->Reset(), VCI_E_ACCESSDENIED);
  fifo.reader->AssignEvent(nullptr);
  fifo.reader->Release();
  fifo.reader.p = nullptr;
  fifo.writer->Release();
  fifo.writer.p = nullptr;
  ASSERT_EQ(whole->Reset(), VCI_OK);
  ASSERT_EQ(whole->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
}

// A FIFO made with VciCreateFifo is reached from another process by its VCIID; there is one
// reader and one writer in all processes together.
TEST(VciCppApi, AFifoIsSharedBetweenProcessesWithOneReaderAndOneWriterInAll) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoWriter> writer;
  ASSERT_EQ(VciCreateFifo(&id, 16, 8, IID_IFifoWriter, writer.pv()), VCI_OK);
  for (uint8_t k = 1; k <= 3; ++k) {
    uint8_t e[8] = {k};
    ASSERT_EQ(writer->PutDataEntry(e), VCI_OK);
  }
  // Another program: the reader, the three elements in order; the writer is the first's.
  ASSERT_NO_FATAL_FAILURE(in_another_program(d, [&id] {
    IFifoReader* reader = nullptr;
    if (VciAccessFifo(id, IID_IFifoReader, reinterpret_cast<PVOID*>(&reader)) != VCI_OK) {
      return 11;
    }
    IFifoWriter* second = nullptr;
    if (VciAccessFifo(id, IID_IFifoWriter, reinterpret_cast<PVOID*>(&second)) !=
        VCI_E_ACCESSDENIED) {
      return 12;
    }
    for (uint8_t k = 1; k <= 3; ++k) {
      uint8_t e[8] = {};
      if (reader->GetDataEntry(e) != VCI_OK || e[0] != k) {
        return 13;
      }
    }
    reader->Release();
    return 0;
  }));
  // The reader is free again, and the FIFO empty.
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciAccessFifo(id, IID_IFifoReader, reader.pv()), VCI_OK);
  UINT16 fill = 1;
  ASSERT_EQ(reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  VCIID unknown{};
  unknown.AsInt64 = 999;
  Ref<IVciFifo> none;
  EXPECT_EQ(VciAccessFifo(unknown, IID_IVciFifo, none.pv()), VCI_E_INVALIDARG);
}

TEST(VciCppApi, TwoProcessesOpenTheSameBalAndAFifoRoundsToWholePages) {
  VciDaemon d;
  Adapter alpha("alpha");  // this process holds alpha's BAL, control unit and a channel
  ASSERT_NO_FATAL_FAILURE(with_alpha_bal_in_another_program(d, [](IBalObject* bal) {
    ICanSocket* socket = nullptr;
    ICanChannel* channel = nullptr;
    if (bal->OpenSocket(0, IID_ICanSocket, reinterpret_cast<PVOID*>(&socket)) != VCI_OK ||
        socket->CreateChannel(FALSE, &channel) != VCI_OK) {
      return 12;
    }
    ICanControl* control = nullptr;
    if (bal->OpenSocket(0, IID_ICanControl, reinterpret_cast<PVOID*>(&control)) !=
        VCI_E_ACCESSDENIED) {
      return 13;  // the first process has the control unit
    }
    return 0;
  }));
  // The guide's 32 elements of 16 bytes: one 4 KiB page holds the 256-byte header and 240.
  VCIID fifo_id{};
  Ref<IVciFifo> fifo;
  ASSERT_EQ(VciCreateFifo(&fifo_id, 32, 16, IID_IVciFifo, fifo.pv()), VCI_OK);
  UINT16 capacity = 0;
  ASSERT_EQ(fifo->GetCapacity(&capacity), VCI_OK);
  EXPECT_EQ(capacity, 240);
}

TEST(VciCppApi, AThreadWaitsForTheFifoLockTheOtherHolds) {
  VciDaemon d;
  VCIID id{};
  Ref<IFifoReader> reader;
  ASSERT_EQ(VciCreateFifo(&id, 16, 8, IID_IFifoReader, reader.pv()), VCI_OK);
  std::vector<int> order;
  std::atomic<bool> trying{false};
  ASSERT_EQ(reader->Lock(), VCI_OK);
  std::thread other([&] {
    trying = true;
    reader->Lock();  // waits for the main thread's Unlock
    order.push_back(2);
    reader->Unlock();
  });
  while (!trying) {
    std::this_thread::yield();
  }
  order.push_back(1);
  ASSERT_EQ(reader->Unlock(), VCI_OK);
  other.join();
  EXPECT_EQ(order, (std::vector<int>{1, 2}));
}

TEST(VciCppApi, FifoEdgesFullEmptyInPlaceWritesLevelsAndThresholds) {
  VciDaemon d;
  StandAloneFifo fifo(16, 8);
  UINT16 capacity = 0;
  ASSERT_EQ(fifo.reader->GetCapacity(&capacity), VCI_OK);
  UINT16 size = 0;
  ASSERT_EQ(fifo.reader->GetEntrySize(&size), VCI_OK);
  EXPECT_EQ(size, 8);
  // Thresholds above the capacity are clamped.
  ASSERT_EQ(fifo.reader->SetThreshold(0xFFFF), VCI_OK);
  UINT16 threshold = 0;
  ASSERT_EQ(fifo.reader->GetThreshold(&threshold), VCI_OK);
  EXPECT_EQ(threshold, capacity);
  // Reading an empty FIFO; acquiring without a place to put the pointer.
  uint8_t e[8] = {};
  EXPECT_EQ(fifo.reader->GetDataEntry(e), VCI_E_RXQUEUE_EMPTY);
  PVOID p = nullptr;
  UINT16 n = 0;
  EXPECT_EQ(fifo.reader->AcquireRead(&p, &n), VCI_E_RXQUEUE_EMPTY);
  EXPECT_EQ(fifo.reader->AcquireRead(nullptr, &n), VCI_E_INVALIDARG);
  // Written in place: invisible until released.
  ASSERT_EQ(fifo.writer->AcquireWrite(&p, &n), VCI_OK);
  EXPECT_EQ(n, capacity);
  static_cast<uint8_t*>(p)[0] = 0x42;
  UINT16 fill = 1;
  ASSERT_EQ(fifo.reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 0);
  ASSERT_EQ(fifo.writer->ReleaseWrite(1), VCI_OK);
  ASSERT_EQ(fifo.reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, 1);
  // Full: the writer is refused, nothing is overwritten; the level says 100 %.
  for (UINT16 k = 1; k < capacity; ++k) {
    e[0] = static_cast<uint8_t>(k);
    ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  }
  EXPECT_EQ(fifo.writer->PutDataEntry(e), VCI_E_TXQUEUE_FULL);
  EXPECT_EQ(fifo.writer->AcquireWrite(&p, &n), VCI_E_TXQUEUE_FULL);
  UINT16 level = 0;
  ASSERT_EQ(fifo.info->GetFillLevel(&level), VCI_OK);
  EXPECT_EQ(level, 100);
  ASSERT_EQ(fifo.reader->GetDataEntry(e), VCI_OK);
  EXPECT_EQ(e[0], 0x42);
  // A second AssignEvent replaces the first.
  const Event first;
  const Event second;
  ASSERT_EQ(fifo.reader->SetThreshold(1), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(first), VCI_OK);
  ASSERT_EQ(fifo.reader->AssignEvent(second), VCI_OK);
  e[0] = 0x99;
  ASSERT_EQ(fifo.writer->PutDataEntry(e), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(second, 5000), WAIT_OBJECT_0);
  EXPECT_EQ(WaitForSingleObject(first, 0), WAIT_TIMEOUT);
  fifo.reader->AssignEvent(nullptr);
}

TEST(VciCppApi, AWritersEventFiresWhenTheControllerMakesRoom) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  UINT16 capacity = 0;
  ASSERT_EQ(alpha.writer->GetCapacity(&capacity), VCI_OK);
  for (UINT32 k = 0; k < 10; ++k) {
    CANMSG m = one_byte(0x300 + k, static_cast<UINT8>(k));
    ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
  }
  UINT16 free_count = 0;
  ASSERT_EQ(alpha.writer->GetFreeCount(&free_count), VCI_OK);
  // Ten put; the line may have taken the first already (the writer rang its doorbell).
  EXPECT_GE(free_count + 10, capacity);
  EXPECT_LE(free_count + 9, capacity);
  const Event event;
  ASSERT_EQ(alpha.writer->SetThreshold(capacity), VCI_OK);  // all free again
  ASSERT_EQ(alpha.writer->AssignEvent(event), VCI_OK);
  EXPECT_EQ(WaitForSingleObject(event, 0), WAIT_TIMEOUT);
  step_ns(10'000'000);  // the line takes all ten
  EXPECT_EQ(WaitForSingleObject(event, 5000), WAIT_OBJECT_0);
  ASSERT_EQ(alpha.writer->GetFreeCount(&free_count), VCI_OK);
  EXPECT_EQ(free_count, capacity);
  alpha.writer->AssignEvent(nullptr);
}

TEST(VciCppApi, EchoesOverrunAndDelayThroughTheFifos) {
  VciDaemon d;
  Adapter alpha("alpha");
  Adapter beta("beta");
  drain(alpha.reader.p, false);
  CANMSG own = one_byte(0x321, 7);
  own.uMsgInfo.Bits.srr = 1;
  ASSERT_EQ(alpha.writer->PutDataEntry(&own), VCI_OK);
  CANMSG later = one_byte(0x322, 8);
  later.dwTime = 500;  // 500 us after the echo's frame was handed over
  ASSERT_EQ(alpha.writer->PutDataEntry(&later), VCI_OK);
  step_ns(5'000'000);
  const auto echo = drain(alpha.reader.p, true);
  ASSERT_EQ(echo.size(), 1u);
  EXPECT_EQ(echo[0].uMsgInfo.Bits.srr, 1u);
  EXPECT_EQ(echo[0].dwTime, end_of(0x321, {7}));
  const auto at_beta = drain(beta.reader.p, true);
  ASSERT_EQ(at_beta.size(), 2u);
  EXPECT_EQ(at_beta[1].dwTime, 500u + end_of(0x322, {8}));
  // beta's receive FIFO holds 1024 or a little more; 1100 frames overflow it.
  UINT16 capacity = 0;
  ASSERT_EQ(beta.reader->GetCapacity(&capacity), VCI_OK);
  for (int k = 0; k <= capacity; k += 64) {
    for (int i = 0; i < 64; ++i) {
      CANMSG m = one_byte(0x400, static_cast<UINT8>(i));
      ASSERT_EQ(alpha.writer->PutDataEntry(&m), VCI_OK);
    }
    step_ns(10'000'000);
  }
  CANCHANSTATUS s{};
  ASSERT_EQ(beta.channel->GetStatus(&s), VCI_OK);
  EXPECT_TRUE(s.fRxOverrun);
  EXPECT_EQ(s.bRxFifoLoad, 100);
  UINT16 fill = 0;
  ASSERT_EQ(beta.reader->GetFillCount(&fill), VCI_OK);
  EXPECT_EQ(fill, capacity);
  drain(beta.reader.p, false);
  CANMSG next = one_byte(0x401, 1);
  ASSERT_EQ(alpha.writer->PutDataEntry(&next), VCI_OK);
  step_ns(1'000'000);
  const auto after = drain(beta.reader.p, true);
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].uMsgInfo.Bits.ovr, 1u);
}

}  // namespace
}  // namespace canemu::testing
