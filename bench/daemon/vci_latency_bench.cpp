// The latency a VCI C program sees (libvcinpl: CANMSG), in real time: one IXXAT adapter's
// channel posts a frame (canChannelPostMessage), another adapter's channel on the same 1 Mbit/s
// bus waits for it in canChannelReadMessage with a timeout, in canChannelWaitRxEvent followed by
// canChannelPeekMessage, or by calling canChannelPeekMessage in a loop (a polling program); the
// figure is the time from the post until the wait
// returns with the frame, minus the frame's own time on the wire. The VCI libraries block on
// the receive ring's eventfd at once (no spin), so this is the same check as the spin sweep of
// BM_ClientDaemonClientLatencyRealtime (daemon_bench) for what VCI programs run.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "../../tests/support/canemud_process.hpp"
#include "../support/latency.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu_vci.h"
#include "vcinpl.h"

namespace {

using namespace canemu;

VCIID id_of(const std::string& name) {
  HANDLE e = nullptr;
  VCIID id{};
  if (vciEnumDeviceOpen(&e) != VCI_OK) {
    return id;
  }
  VCIDEVICEINFO info{};
  while (vciEnumDeviceNext(e, &info) == VCI_OK) {
    if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
      id = info.VciObjectId;
    }
  }
  vciEnumDeviceClose(e);
  return id;
}

// An adapter's controller at 1 Mbit/s with one started channel, as a VCI program opens it.
struct Adapter {
  HANDLE device = nullptr;
  HANDLE control = nullptr;
  HANDLE channel = nullptr;
  bool ok = false;
  explicit Adapter(const std::string& name) {
    ok = vciDeviceOpen(id_of(name), &device) == VCI_OK &&
         canControlOpen(device, 0, &control) == VCI_OK &&
         canChannelOpen(device, 0, FALSE, &channel) == VCI_OK &&
         canChannelInitialize(channel, 1024, 1, 64, 1) == VCI_OK &&
         canChannelActivate(channel, TRUE) == VCI_OK &&
         canControlInitialize(control, CAN_OPMODE_STANDARD, CAN_BT0_1000KB, CAN_BT1_1000KB) ==
             VCI_OK &&
         canControlStart(control, TRUE) == VCI_OK;
  }
  Adapter(const Adapter&) = delete;
  Adapter& operator=(const Adapter&) = delete;
  ~Adapter() {
    if (channel != nullptr) {
      canChannelClose(channel);
    }
    if (control != nullptr) {
      canControlClose(control);
    }
    if (device != nullptr) {
      vciDeviceClose(device);
    }
  }
};

// range(0): 0 waits in canChannelReadMessage, 1 in canChannelWaitRxEvent + canChannelPeekMessage,
// 2 polls canChannelPeekMessage.
void BM_VciCLatencyRealtime(benchmark::State& state) {
  char dir[] = "/tmp/canemu-bench-XXXXXX";
  const std::string folder = ::mkdtemp(dir);
  const std::string config = folder + "/vci.toml";
  {
    std::ofstream f(config);
    f << "[simulation]\ntime = \"realtime\"\n\n[[bus]]\nname = \"fast\"\nbitrate = 1000000\n\n"
         "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"fast\"]\n\n"
         "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"fast\"]\n";
  }
  {
    testing::CanemudProcess daemon(CANEMUD_PATH, {"--config=" + config});
    if (!daemon.ready() || canemuConnect(daemon.socket().c_str()) != VCI_OK) {
      state.SkipWithError(("canemud did not start: " + daemon.log()).c_str());
      return;
    }
    {
      Adapter a("alpha");
      Adapter b("beta");
      if (!a.ok || !b.ok) {
        state.SkipWithError("the adapters did not open");
        return;
      }
      const int64_t how = state.range(0);
      CANMSG m{};
      m.dwMsgId = 0x123;
      m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
      m.uMsgInfo.Bits.dlc = 8;
      for (uint8_t k = 0; k < 8; ++k) {
        m.abData[k] = static_cast<uint8_t>(0x11 * (k + 1));
      }
      const auto frame = model::Frame::classic(0x123, std::span<const uint8_t>(m.abData, 8));
      const int64_t wire_ns = int64_t{model::encode(*frame).length} * 1000;
      std::vector<int64_t> beyond;
      for (auto _ : state) {
        for (std::size_t i = 0; i < bench::kLatencySamples; ++i) {
          bench::sleep_ns(bench::kLatencyGapNs);
          CANMSG out = m;
          const int64_t t0 = bench::now_ns();
          if (canChannelPostMessage(a.channel, &out) != VCI_OK) {
            state.SkipWithError("canChannelPostMessage failed");
            break;
          }
          CANMSG got{};
          HRESULT hr = VCI_OK;
          do {  // data frames only (the controller's start leaves an info message)
            if (how == 1) {
              hr = canChannelWaitRxEvent(b.channel, 1000);
              if (hr == VCI_OK) {
                hr = canChannelPeekMessage(b.channel, &got);
              }
            } else if (how == 2) {
              const int64_t give_up = t0 + 1'000'000'000;
              while ((hr = canChannelPeekMessage(b.channel, &got)) == VCI_E_RXQUEUE_EMPTY &&
                     bench::now_ns() < give_up) {
              }
            } else {
              hr = canChannelReadMessage(b.channel, 1000, &got);
            }
          } while (hr == VCI_OK && got.uMsgInfo.Bytes.bType != CAN_MSGTYPE_DATA);
          const int64_t t1 = bench::now_ns();
          if (hr != VCI_OK) {
            state.SkipWithError("the frame did not arrive");
            break;
          }
          beyond.push_back(t1 - t0 - wire_ns);
        }
      }
      state.counters["frame_wire_us"] = static_cast<double>(wire_ns) / 1000.0;
      bench::report(state, "beyond_frame", beyond);
    }
    canemuConnect(nullptr);
  }
  std::remove(config.c_str());
  ::rmdir(dir);
}
BENCHMARK(BM_VciCLatencyRealtime)
    ->ArgName("wait")  // 0 ReadMessage, 1 WaitRxEvent + PeekMessage, 2 PeekMessage polled
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
