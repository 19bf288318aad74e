// Stand-alone VCI FIFOs between clients: created by one, reached by id by others of the same
// user, one reader and one writer in all, freed (and its memory given back) when nobody holds it.
#include "canemu/daemon/vci/vci_fifos.hpp"

#include <gtest/gtest.h>

#include "vci/vcierr.h"

namespace canemu::daemon {
namespace {

struct Fifos {
  RingLedger rings;
  VciFifos fifos{rings};
  int a = 0;  // two clients of one user, by address
  int b = 0;
  int stranger = 0;  // a client of another user
  int root = 0;      // a client of root
  uint32_t uid_of(VciFifos::Holder who) const {
    return who == &stranger ? 1001 : who == &root ? 0 : 1000;
  }

  ipc::VciReply call(VciFifos::Holder who, ipc::VciOp op, uint32_t a0, uint32_t a1, uint32_t a2 = 0,
                     uint32_t a3 = 0, std::vector<int>* fds = nullptr) {
    ipc::VciRequest m{};
    m.op = static_cast<uint16_t>(op);
    m.args[0] = a0;
    m.args[1] = a1;
    m.args[2] = a2;
    m.args[3] = a3;
    ipc::VciReply r{};
    std::vector<int> unused;
    fifos.handle(who, uid_of(who), m, r, fds != nullptr ? *fds : unused);
    return r;
  }
  ipc::VciReply create(VciFifos::Holder who, uint32_t capacity, uint32_t size,
                       std::vector<int>* fds = nullptr) {
    return call(who, ipc::VciOp::fifo_create, capacity, size, 0, 0, fds);
  }
  ipc::VciReply access(VciFifos::Holder who, uint64_t id, std::vector<int>* fds = nullptr) {
    return call(who, ipc::VciOp::fifo_access, static_cast<uint32_t>(id),
                static_cast<uint32_t>(id >> 32), 0, 0, fds);
  }
  static uint64_t id_of(const ipc::VciReply& r) {
    return uint64_t{r.values[0]} | (uint64_t{r.values[1]} << 32);
  }
  HRESULT side(VciFifos::Holder who, uint64_t id, uint32_t which, bool take) {
    return call(who, ipc::VciOp::fifo_side, static_cast<uint32_t>(id),
                static_cast<uint32_t>(id >> 32), which, take ? 1 : 0)
        .hresult;
  }
};

TEST(VciFifos, CreatingGivesTheIdTheRoundedCapacityAndTheThreeDescriptors) {
  Fifos f;
  std::vector<int> fds;
  const ipc::VciReply r = f.create(&f.a, 32, 20, &fds);
  ASSERT_EQ(r.hresult, VCI_OK);
  const uint64_t id = Fifos::id_of(r);
  EXPECT_NE(id, 0u);
  EXPECT_EQ(r.values[2], 192u);  // one page: (4096 - 256) / 20
  EXPECT_EQ(r.values[3], 20u);
  ASSERT_EQ(fds.size(), ipc::kFifoFdCount);
  EXPECT_EQ(f.rings.in_use(), 192u * 20);
  const uint64_t second = Fifos::id_of(f.create(&f.a, 1, 8));
  EXPECT_NE(second, id);
  EXPECT_NE(second, id + 1);  // not sequential
  EXPECT_EQ(f.access(&f.b, id + 1).hresult, VCI_E_INVALIDARG);
  EXPECT_EQ(f.fifos.count(), 2u);
}

TEST(VciFifos, OneUserHoldsAtMostItsRingQuotaAndOtherUsersKeepTheirs) {
  Fifos f;
  f.rings.set_user_quota(std::size_t{1} << 20);
  // 4096 elements of 200 bytes: 800 KiB, counted as held by uid 1000.
  ASSERT_EQ(f.create(&f.a, 4096, 200).hresult, VCI_OK);
  EXPECT_EQ(f.rings.in_use(1000), f.rings.in_use());
  EXPECT_GE(f.rings.in_use(1000), 4096u * 200);
  // Another client of the same user shares the quota: 800 KiB more do not fit.
  EXPECT_EQ(f.create(&f.b, 4096, 200).hresult, VCI_E_OUTOFMEMORY);
  EXPECT_EQ(f.fifos.count(), 1u);                                 // nothing changed
  EXPECT_NE(f.create(&f.b, 64, 200).hresult, VCI_E_OUTOFMEMORY);  // what is left still fits
  // Another user has a quota of its own; root has none (only the daemon-wide limit).
  EXPECT_EQ(f.create(&f.stranger, 4096, 200).hresult, VCI_OK);
  EXPECT_EQ(f.create(&f.root, 0xFFFF, 200).hresult, VCI_OK);
  EXPECT_EQ(f.create(&f.root, 0xFFFF, 0xFFFF).hresult, VCI_E_OUTOFMEMORY);  // 4 GiB > 256 MiB
  f.fifos.release(&f.a);
  f.fifos.release(&f.b);
  EXPECT_EQ(f.rings.in_use(1000), 0u);
  EXPECT_EQ(f.create(&f.a, 4096, 200).hresult, VCI_OK);  // given back
}

TEST(VciFifos, BadSizesAndUnknownIdsAreInvalidArguments) {
  Fifos f;
  EXPECT_EQ(f.create(&f.a, 0, 20).hresult, VCI_E_INVALIDARG);
  EXPECT_EQ(f.create(&f.a, 0x10000, 20).hresult, VCI_E_INVALIDARG);
  EXPECT_EQ(f.create(&f.a, 8, 0).hresult, VCI_E_INVALIDARG);
  EXPECT_EQ(f.access(&f.a, 99).hresult, VCI_E_INVALIDARG);
  EXPECT_EQ(f.side(&f.a, 99, 0, true), VCI_E_INVALIDARG);
  EXPECT_EQ(f.fifos.count(), 0u);
}

TEST(VciFifos, EachSideHasOneHolderAtATimeAmongAllClients) {
  Fifos f;
  const uint64_t id = Fifos::id_of(f.create(&f.a, 8, 8));
  EXPECT_EQ(f.side(&f.b, id, 0, true), VCI_E_INVALIDARG);  // b does not hold the FIFO yet
  ASSERT_EQ(f.access(&f.b, id).hresult, VCI_OK);
  EXPECT_EQ(f.side(&f.a, id, 0, true), VCI_OK);  // a reads
  EXPECT_EQ(f.side(&f.b, id, 0, true), VCI_E_ACCESSDENIED);
  EXPECT_EQ(f.side(&f.b, id, 1, true), VCI_OK);             // b writes
  EXPECT_EQ(f.side(&f.b, id, 0, false), VCI_E_INVALIDARG);  // not b's to give back
  EXPECT_EQ(f.side(&f.a, id, 0, false), VCI_OK);
  EXPECT_EQ(f.side(&f.b, id, 0, true), VCI_OK);
  EXPECT_EQ(f.side(&f.a, id, 2, true), VCI_E_INVALIDARG);  // sides are 0 and 1
}

TEST(VciFifos, AFifoLivesWhileAClientHoldsItAndALeavingClientGivesBackItsSides) {
  Fifos f;
  const uint64_t id = Fifos::id_of(f.create(&f.a, 8, 8));
  ASSERT_EQ(f.access(&f.b, id).hresult, VCI_OK);
  ASSERT_EQ(f.side(&f.a, id, 1, true), VCI_OK);
  const std::size_t bytes = f.rings.in_use();
  f.fifos.release(&f.a);
  EXPECT_EQ(f.fifos.count(), 1u);  // b still holds it
  EXPECT_EQ(f.rings.in_use(), bytes);
  EXPECT_EQ(f.side(&f.b, id, 1, true), VCI_OK);  // a's writer side was given back
  f.fifos.release(&f.b);
  EXPECT_EQ(f.fifos.count(), 0u);
  EXPECT_EQ(f.rings.in_use(), 0u);
  EXPECT_EQ(f.access(&f.a, id).hresult, VCI_E_INVALIDARG);  // gone for good
}

TEST(VciFifos, AClientHoldsAtMost64) {
  Fifos f;
  uint64_t first = 0;
  for (std::size_t k = 0; k < kMaxVciFifosPerClient; ++k) {
    const ipc::VciReply r = f.create(&f.a, 1, 8);
    ASSERT_EQ(r.hresult, VCI_OK);
    first = k == 0 ? Fifos::id_of(r) : first;
  }
  EXPECT_EQ(f.create(&f.a, 1, 8).hresult, VCI_E_OUTOFMEMORY);
  const uint64_t other = Fifos::id_of(f.create(&f.b, 1, 8));
  EXPECT_EQ(f.access(&f.a, other).hresult, VCI_E_OUTOFMEMORY);
  EXPECT_EQ(f.access(&f.a, first).hresult, VCI_OK);  // one it holds already is no new one
}

// A FIFO's id reaches only clients of the creator's user (and root): another user's client is
// refused whatever it asks, and changes nothing.
TEST(VciFifos, AnotherUsersClientCannotUseTheFifo) {
  Fifos f;
  const uint64_t id = Fifos::id_of(f.create(&f.a, 8, 8));
  EXPECT_EQ(f.access(&f.stranger, id).hresult, VCI_E_ACCESSDENIED);
  EXPECT_EQ(f.side(&f.stranger, id, 0, true), VCI_E_ACCESSDENIED);
  EXPECT_EQ(f.side(&f.a, id, 0, true), VCI_OK);  // the reader side was not taken
  EXPECT_EQ(f.access(&f.root, id).hresult, VCI_OK);
  EXPECT_EQ(f.access(&f.b, id).hresult, VCI_OK);
}

}  // namespace
}  // namespace canemu::daemon
