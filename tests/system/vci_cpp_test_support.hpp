// What the tests of the VCI C++ API (libvciapi: vcisdk.h) share: references that release what
// they hold, an adapter opened the way the guide's walk-through opens it, and messages and
// their time on the wire.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcisdk.h"

namespace canemu::testing {

template <class T>
struct Ref {  // releases what it holds
  T* p = nullptr;
  Ref() = default;
  Ref(Ref&& other) noexcept : p(other.p) { other.p = nullptr; }
  Ref(const Ref&) = delete;
  Ref& operator=(const Ref&) = delete;
  ~Ref() {
    if (p != nullptr) {
      p->Release();
    }
  }
  T* operator->() const { return p; }
  T** out() { return &p; }
  PVOID* pv() { return reinterpret_cast<PVOID*>(&p); }
};

// An auto-reset event (CreateEvent), closed with the object; it converts to its handle.
class Event {
 public:
  Event() = default;
  Event(const Event&) = delete;
  Event& operator=(const Event&) = delete;
  ~Event() { CloseHandle(handle_); }
  operator HANDLE() const { return handle_; }

 private:
  HANDLE handle_ = CreateEvent(nullptr, FALSE, FALSE, nullptr);
};

// A stand-alone FIFO of `capacity` elements of `size` bytes: its writer from VciCreateFifo, its
// reader and its IVciFifo (capacity, levels) from VciAccessFifo.
struct StandAloneFifo {
  VCIID id{};
  Ref<IFifoWriter> writer;
  Ref<IFifoReader> reader;
  Ref<IVciFifo> info;
  StandAloneFifo(UINT16 capacity, UINT16 size) {
    EXPECT_EQ(VciCreateFifo(&id, capacity, size, IID_IFifoWriter, writer.pv()), VCI_OK);
    EXPECT_EQ(VciAccessFifo(id, IID_IFifoReader, reader.pv()), VCI_OK);
    EXPECT_EQ(VciAccessFifo(id, IID_IVciFifo, info.pv()), VCI_OK);
  }
};

// The VciObjectId of the adapter named `name` (0 if there is none), from the device manager.
inline INT64 vci_id_named(const std::string& name) {
  Ref<IVciDeviceManager> manager;
  EXPECT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  Ref<IVciEnumDevice> e;
  EXPECT_EQ(manager->EnumDevices(e.out()), VCI_OK);
  VCIDEVICEINFO info{};
  while (e->Next(1, &info, nullptr) == VCI_OK) {
    if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
      return info.VciObjectId.AsInt64;
    }
  }
  return 0;
}

inline constexpr UINT8 kMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;

// Opens the adapter named `name` the way the guide's walk-through does.
struct Adapter {
  Ref<IVciDevice> device;
  Ref<IBalObject> bal;
  Ref<ICanSocket> socket;
  Ref<ICanChannel> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  Ref<ICanControl> control;
  explicit Adapter(const std::string& name) {
    Ref<IVciDeviceManager> manager;
    EXPECT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
    VCIID id{};
    id.AsInt64 = vci_id_named(name);
    EXPECT_EQ(manager->OpenDevice(id, device.out()), VCI_OK);
    EXPECT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
    EXPECT_EQ(channel->Initialize(1024, 128), VCI_OK);
    EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
    EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    EXPECT_EQ(channel->Activate(), VCI_OK);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanControl, control.pv()), VCI_OK);
    CANINITLINE init{kMode, 0, CAN_BT0_500KB, CAN_BT1_500KB};
    EXPECT_EQ(control->InitLine(&init), VCI_OK);
    EXPECT_EQ(control->StartLine(), VCI_OK);
  }
  // Resets the line and initializes it again (kMode) at `btr0`/`btr1`, not yet started.
  void reinit(UINT8 btr0, UINT8 btr1) const {
    ASSERT_EQ(control->ResetLine(), VCI_OK);
    CANINITLINE init{kMode, 0, btr0, btr1};
    ASSERT_EQ(control->InitLine(&init), VCI_OK);
  }
  // Stops the line and shuts the acceptance filter of `width` (CAN_FILTER_STD or CAN_FILTER_EXT):
  // only the identifiers of its list pass then.
  void stop_with_list_only(UINT8 width) const {
    ASSERT_EQ(control->StopLine(), VCI_OK);
    ASSERT_EQ(control->SetAccFilter(width, CAN_ACC_CODE_NONE, CAN_ACC_MASK_NONE), VCI_OK);
  }
  // stop_with_list_only, the list holding `id` alone (data frames, not remote ones).
  void stop_and_pass_only(UINT8 width, UINT32 id) const {
    ASSERT_NO_FATAL_FAILURE(stop_with_list_only(width));
    const UINT32 mask = width == CAN_FILTER_STD ? 0xFFF : 0x3FFFFFFF;  // the identifier and RTR
    ASSERT_EQ(control->AddFilterIds(width, id << 1, mask), VCI_OK);
  }
  CANLINESTATUS line_status() const {
    CANLINESTATUS s{};
    EXPECT_EQ(control->GetLineStatus(&s), VCI_OK);
    return s;
  }
  // The controller's cyclic transmit list.
  Ref<ICanScheduler> scheduler() const {
    Ref<ICanScheduler> list;
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanScheduler, list.pv()), VCI_OK);
    return list;
  }
};

// canemud on kTwoAdapters with alpha and beta opened as a program opens them: where most tests
// start.
struct TwoAdapters {
  VciDaemon d;
  Adapter alpha{"alpha"};
  Adapter beta{"beta"};
};

// The BAL of the adapter whose VciObjectId is `id`, opened through the device manager.
inline void open_bal(INT64 id, Ref<IBalObject>& bal) {
  Ref<IVciDeviceManager> manager;
  ASSERT_EQ(VciGetDeviceManager(manager.out()), VCI_OK);
  VCIID vciid{};
  vciid.AsInt64 = id;
  Ref<IVciDevice> device;
  ASSERT_EQ(manager->OpenDevice(vciid, device.out()), VCI_OK);
  ASSERT_EQ(device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, bal.pv()), VCI_OK);
}

// Runs `body` (-> int) in a child process with a connection of its own to `d`'s canemud, as
// another program; the child's exit code is what `body` returns (0: all was as expected), 10 when
// it could not connect.
template <class Body>
void in_another_program(const VciDaemon& d, Body body) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (canemuConnect(d.daemon.socket().c_str()) != VCI_OK) {
      ::_exit(10);
    }
    ::_exit(body());
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// in_another_program with alpha's BAL (VciObjectId 1) opened for `body` (IBalObject* -> int);
// 11 when it could not be opened.
template <class Body>
void with_alpha_bal_in_another_program(const VciDaemon& d, Body body) {
  in_another_program(d, [&] {
    IVciDeviceManager* manager = nullptr;
    IVciDevice* device = nullptr;
    IBalObject* bal = nullptr;
    VCIID id{};
    id.AsInt64 = 1;
    if (VciGetDeviceManager(&manager) != VCI_OK || manager->OpenDevice(id, &device) != VCI_OK ||
        device->OpenComponent(CLSID_VCIBAL, IID_IBalObject, reinterpret_cast<PVOID*>(&bal)) !=
            VCI_OK) {
      return 11;
    }
    return body(bal);
  });
}

// A channel made on `socket` and initialized (receive FIFO `rx`, transmit FIFO `tx`: none if 0),
// with its reader and, given a transmit FIFO, its writer; activated if asked.
struct Channel {
  Ref<ICanChannel> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  Channel(ICanSocket* socket, UINT16 rx, UINT16 tx, bool activate) {
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
    EXPECT_EQ(channel->Initialize(rx, tx), VCI_OK);
    EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
    if (tx > 0) {
      EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    }
    if (activate) {
      EXPECT_EQ(channel->Activate(), VCI_OK);
    }
  }
};

// A channel made through the v2 interfaces of `bal`: the socket and the channel, not yet
// initialized.
struct V2Channel {
  Ref<ICanSocket2> socket;
  Ref<ICanChannel2> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  explicit V2Channel(IBalObject* bal) {
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
  }
  // Initializes the channel in filter mode `mode` (receive FIFO `rx`, transmit FIFO `tx`: none
  // if 0; no filter list), takes its reader and, given a transmit FIFO, its writer, and
  // activates it.
  void activate_with(UINT16 rx, UINT16 tx, UINT8 mode) {
    ASSERT_EQ(channel->Initialize(rx, tx, 0, mode), VCI_OK);
    ASSERT_EQ(channel->GetReader(reader.out()), VCI_OK);
    if (tx > 0) {
      ASSERT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    }
    ASSERT_EQ(channel->Activate(), VCI_OK);
  }
};

// The socket `I` (ICanSocket, ICanSocket2, ...) of the adapter named `name`'s first controller,
// on a BAL opened for it.
template <class I>
struct BalSocket {
  Ref<IBalObject> bal;
  Ref<I> socket;
  BalSocket(const std::string& name, REFIID iid) {
    open_bal(vci_id_named(name), bal);
    EXPECT_EQ(bal->OpenSocket(0, iid, socket.pv()), VCI_OK);
  }
};

// The one message of `msgs`: a failure when there is not exactly one.
template <class Msg>
Msg the_one(const std::vector<Msg>& msgs) {
  EXPECT_EQ(msgs.size(), 1u);
  return msgs.size() == 1 ? msgs[0] : Msg{};
}

// `device`'s info, and the info of the device VciQueryDeviceByHwid opens by its hardware ID.
inline void query_by_hwid(IVciDevice* device, VCIDEVICEINFO* info, VCIDEVICEINFO* found) {
  ASSERT_EQ(device->GetDeviceInfo(info), VCI_OK);
  Ref<IVciDevice> same;
  ASSERT_EQ(VciQueryDeviceByHwid(info->UniqueHardwareId.AsGuid, same.out()), VCI_OK);
  ASSERT_EQ(same->GetDeviceInfo(found), VCI_OK);
}

inline CANMSG one_byte(UINT32 id, UINT8 b) {
  CANMSG m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = 1;
  m.abData[0] = b;
  return m;
}

// What `reader` holds, taken out as `Msg` (CANMSG or CANMSG2; `data_only`: only the data
// frames).
template <class Msg = CANMSG>
inline std::vector<Msg> drain(IFifoReader* reader, bool data_only) {
  std::vector<Msg> got;
  Msg m;
  while (reader->GetDataEntry(&m) == VCI_OK) {
    if (!data_only || m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      got.push_back(m);
    }
  }
  return got;
}

inline constexpr CANBTP kNominal{0, 500000, 14, 2, 1, 0};  // 16 quanta
inline constexpr CANBTP kData{0, 2000000, 8, 2, 1, 0};     // 10 quanta

// An adapter's controller through the v2 interfaces: a PASS channel with its reader and writer,
// the control unit initialized with `op_mode` and `ex_mode` (500 kbit/s, and 2 Mbit/s with
// FASTDATA) and started.
struct V2Adapter {
  Ref<IBalObject> bal;
  Ref<ICanSocket2> socket;
  Ref<ICanChannel2> channel;
  Ref<IFifoReader> reader;
  Ref<IFifoWriter> writer;
  Ref<ICanControl2> control;
  UINT8 op_mode;
  V2Adapter(const std::string& name, UINT8 ex_mode, UINT8 mode = kMode) : op_mode(mode) {
    open_bal(vci_id_named(name), bal);
    EXPECT_EQ(bal->OpenSocket(0, IID_ICanSocket2, socket.pv()), VCI_OK);
    EXPECT_EQ(socket->CreateChannel(FALSE, channel.out()), VCI_OK);
    EXPECT_EQ(channel->Initialize(256, 64, 0, CAN_FILTER_PASS), VCI_OK);
    EXPECT_EQ(channel->GetReader(reader.out()), VCI_OK);
    EXPECT_EQ(channel->GetWriter(writer.out()), VCI_OK);
    EXPECT_EQ(channel->Activate(), VCI_OK);
    EXPECT_EQ(channel->GetControl(control.out()), VCI_OK);
    init(ex_mode);
    EXPECT_EQ(control->StartLine(), VCI_OK);
  }
  void init(UINT8 ex_mode) {
    CANINITLINE2 init{};
    init.bOpMode = op_mode;
    init.bExMode = ex_mode;
    init.bSFMode = CAN_FILTER_PASS;
    init.bEFMode = CAN_FILTER_PASS;
    init.sBtpSdr = kNominal;
    if ((ex_mode & CAN_EXMODE_FASTDATA) != 0) {
      init.sBtpFdr = kData;
    }
    EXPECT_EQ(control->InitLine(&init), VCI_OK);
  }
  void post(CANMSG2 m) const { ASSERT_EQ(writer->PutDataEntry(&m), VCI_OK); }
};

// The end of a classic frame sent at t = 0, in device ticks (us) at 500 kbit/s.
inline UINT32 end_of(uint32_t id, std::vector<uint8_t> data, bool ext = false) {
  return 2u * model::encode(*model::Frame::classic(id, data, ext)).length;  // 2 us a bit
}

}  // namespace canemu::testing
