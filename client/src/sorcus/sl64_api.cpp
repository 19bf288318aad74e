// libsl64.so: the sl064_* functions over canemud's SL-CANi requests (ipc::SlcanRequest), with
// the service routines as functions of the program run on one thread of the library.
#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <iterator>
#include <map>
#include <mutex>
#include <utility>

#include "canemu/client/callback_thread.hpp"
#include "canemu/client/daemon_link.hpp"
#include "sl64lib.h"

namespace canemu::client::sl64 {
namespace {

constexpr unsigned kSlots = SL064_SLOTS;
using Key = std::pair<USHORT, USHORT>;

// Decision: routine calls wait for the routine thread in a queue of at most this many (about
// 2.5 MB); a call that finds it full is dropped and counted for its slot
// (canemu_sl064_lost_calls), as an interrupt the card could not serve.
constexpr std::size_t kMaxQueuedCalls = 65536;

// On the routine thread, while the acceptance mask's routine runs for an unconfigured frame:
// its slot and the frame's ID, which sl064_get_id(slot, 0, ...) passes back to canemud.
thread_local int t_call_slot = -1;
thread_local ULONG t_call_id = 0;

class Library {
 public:
  static Library& get() {
    static Library library;
    return library;
  }

  // One request for `slot`: true with the reply, false (and diagnosis 22h kept for the slot)
  // when the slot is not this program's or canemud cannot be reached or refused it.
  bool call(UCHAR slot, ipc::SlcanRequest& m, ipc::SlcanReply& r) {
    if (!holds(slot)) {
      return no_response(slot);
    }
    m.slot = slot;
    if (link_.call(m, r) != DaemonLink::Outcome::replied) {
      return no_response(slot);
    }
    return true;
  }
  USHORT op(UCHAR slot, ipc::SlcanOp op, ipc::SlcanReply& r,
            const std::function<void(ipc::SlcanRequest&)>& fill = {}) {
    auto m = ipc::make_message<ipc::SlcanRequest>();
    m.op = static_cast<uint16_t>(op);
    if (fill) {
      fill(m);
    }
    return call(slot, m, r) ? r.ret : USHORT{SL064_E_DRIVER};
  }

  USHORT startup() {
    auto m = ipc::make_message<ipc::SlcanRequest>();
    m.op = static_cast<uint16_t>(ipc::SlcanOp::bib_startup);
    ipc::SlcanReply r{};
    if (link_.call(m, r) != DaemonLink::Outcome::replied) {
      std::lock_guard lock(mutex_);
      held_ = 0;
      return SL064_E_DRIVER;
    }
    {
      std::lock_guard lock(mutex_);
      held_ = r.value;
      generation_ = link_.generation();
    }
    routines_.start();
    // The routines installed so far, on every slot now held.
    for (const Key& k : installed()) {
      for (UCHAR s = 0; s < kSlots; ++s) {
        if (holds(s)) {
          send_routine(s, k, true);
        }
      }
    }
    return 0;
  }

  USHORT diagnosis(UCHAR slot) {
    if (!holds(slot)) {
      std::lock_guard lock(mutex_);
      const USHORT d = slot < kSlots ? local_[slot] : USHORT{SL064_DIAG_NO_RESPONSE};
      if (slot < kSlots) {
        local_[slot] = 0;
      }
      return d;
    }
    ipc::SlcanReply r{};
    if (op(slot, ipc::SlcanOp::get_diagnosis, r) != 0) {
      return diagnosis(slot);  // lost meanwhile: the local 22h
    }
    return static_cast<USHORT>(r.value);
  }

  USHORT install(USHORT task, USHORT func, void* routine, bool error) {
    if ((task == 0 && func == 0) ||
        (func == SL064_SRQ_SERVICE_FUNC && task >= 0x40 && task < 0x40 + kSlots)) {
      return SL064_E_DRIVER;
    }
    const Key k{task, func};
    {
      std::lock_guard lock(mutex_);
      if (routine == nullptr) {
        message_.erase(k);
        error_.erase(k);
      } else if (error) {
        error_[k] = reinterpret_cast<SL064ErrorService>(routine);
      } else {
        message_[k] = reinterpret_cast<SL064MessageService>(routine);
      }
    }
    for (UCHAR s = 0; s < kSlots; ++s) {
      if (holds(s)) {
        send_routine(s, k, routine != nullptr);
      }
    }
    return 0;
  }

  USHORT wait_srq(int timeout_ms) {
    std::unique_lock lock(mutex_);
    auto ready = [&] { return !srq_.empty(); };
    if (timeout_ms < 0) {
      srq_ready_.wait(lock, ready);
    } else if (!srq_ready_.wait_for(lock, std::chrono::milliseconds(timeout_ms), ready)) {
      return 0;
    }
    const USHORT w = srq_.front();
    srq_.pop_front();
    return w;
  }

  USHORT connect(const char* socket) {
    {
      // What the old connection's S-Links said is no one's business any more.
      std::lock_guard lock(mutex_);
      held_ = 0;
      srq_.clear();
      std::fill(std::begin(lost_), std::end(lost_), ULONG{0});
    }
    routines_.clear();
    const std::string path = socket != nullptr ? socket : "";
    link_.reconnect(path);
    return path.empty() || link_.connect() ? USHORT{0} : USHORT{SL064_E_DRIVER};
  }

  bool holds(UCHAR slot) {
    std::lock_guard lock(mutex_);
    // A new connection: canemud gave the slots back when the old one broke.
    return slot < kSlots && (held_ & (1u << slot)) != 0 && link_.generation() == generation_;
  }

 private:
  Library()
      : routines_([this](const ipc::SlcanEventMsg& e) { run(e); },
                  CallbackThread<ipc::SlcanEventMsg>::AtEnd::drop_queued, kMaxQueuedCalls),
        link_("sl64", [this](const std::vector<uint8_t>& p) { unsolicited(p); }) {}

  bool no_response(UCHAR slot) {
    std::lock_guard lock(mutex_);
    if (slot < kSlots) {
      local_[slot] = SL064_DIAG_NO_RESPONSE;
    }
    return false;
  }
  std::vector<Key> installed() {
    std::lock_guard lock(mutex_);
    std::vector<Key> out;
    for (const auto& [k, f] : message_) {
      out.push_back(k);
    }
    for (const auto& [k, f] : error_) {
      out.push_back(k);
    }
    return out;
  }
  void send_routine(UCHAR slot, const Key& k, bool on) {
    ipc::SlcanReply r{};
    (void)op(slot, on ? ipc::SlcanOp::install_routine : ipc::SlcanOp::remove_routine, r,
             [&](ipc::SlcanRequest& m) {
               m.task = k.first;
               m.func = k.second;
             });
  }

  // On the receive thread.
  void unsolicited(const std::vector<uint8_t>& p) {
    ipc::MsgHeader h;
    std::memcpy(&h, p.data(), sizeof h);
    if (h.type != static_cast<uint16_t>(ipc::MsgType::slcan_event)) {
      return;
    }
    ipc::SlcanEventMsg e;
    std::memcpy(&e, p.data(), sizeof e);
    if (e.kind == static_cast<uint8_t>(ipc::SlcanEventKind::service_request)) {
      std::lock_guard lock(mutex_);
      srq_.push_back(e.word);
      srq_ready_.notify_all();
      return;
    }
    if (!routines_.push(e)) {
      std::lock_guard lock(mutex_);
      if (e.slot < kSlots) {
        ++lost_[e.slot];
      }
    }
  }

 public:
  ULONG lost_calls(UCHAR slot) {
    std::lock_guard lock(mutex_);
    return slot < kSlots ? lost_[slot] : 0;
  }

 private:
  // On the routine thread: the routine installed for the event's task and function, if any.
  void run(const ipc::SlcanEventMsg& e) {
    std::unique_lock lock(mutex_);
    const Key k{e.task, e.func};
    if (e.kind == static_cast<uint8_t>(ipc::SlcanEventKind::error)) {
      auto it = error_.find(k);
      if (it == error_.end()) {
        return;
      }
      const SL064ErrorService f = it->second;
      lock.unlock();
      ULONG status = e.status;
      f(e.task, sizeof status, &status, 0, nullptr);
      return;
    }
    auto it = message_.find(k);
    if (it == message_.end()) {
      return;
    }
    const SL064MessageService f = it->second;
    lock.unlock();
    SL064Handle handle = e.handle;
    if (handle == 0) {
      t_call_slot = e.slot;  // the mask's routine: its frame's ID for sl064_get_id
      t_call_id = e.status;
    }
    f(e.task, sizeof handle, &handle, 0, nullptr);
    t_call_slot = -1;
  }

  std::mutex mutex_;
  uint32_t held_ = 0;
  uint64_t generation_ = 0;
  USHORT local_[kSlots] = {};
  ULONG lost_[kSlots] = {};  // routine calls dropped on a full queue, since the connection
  std::map<Key, SL064MessageService> message_;
  std::map<Key, SL064ErrorService> error_;
  std::deque<USHORT> srq_;
  std::condition_variable srq_ready_;
  // The routines' calls, in order, at most kMaxQueuedCalls waiting; those still queued at the
  // end are dropped.
  CallbackThread<ipc::SlcanEventMsg> routines_;
  DaemonLink link_;  // last: destroyed first, so no event comes in while the rest goes
};

USHORT simple(UCHAR slot, ipc::SlcanOp op, SL064Handle handle = 0) {
  ipc::SlcanReply r{};
  return Library::get().op(slot, op, r, [&](ipc::SlcanRequest& m) { m.handle = handle; });
}

}  // namespace
}  // namespace canemu::client::sl64

using canemu::client::sl64::Library;
using canemu::client::sl64::simple;
using canemu::ipc::SlcanOp;
using canemu::ipc::SlcanReply;
using canemu::ipc::SlcanRequest;

extern "C" {

USHORT sl064_bib_startup(void) {
  return Library::get().startup();
}

USHORT sl064_config_module(UCHAR micro_slot, USHORT err_task, USHORT err_func) {
  SlcanReply r{};
  return Library::get().op(micro_slot, SlcanOp::config_module, r, [&](SlcanRequest& m) {
    m.task = err_task;
    m.func = err_func;
  });
}

USHORT sl064_config_msg_object(UCHAR micro_slot, SL064Handle* handle, SL064MsgType* config) {
  if (handle == nullptr || config == nullptr) {
    return SL064_E_DRIVER;
  }
  SlcanReply r{};
  const USHORT ret =
      Library::get().op(micro_slot, SlcanOp::config_msg_object, r, [&](SlcanRequest& m) {
        m.value = config->id;
        m.flags = config->control_flags;
        m.task = config->serv_task;
        m.func = config->serv_func;
      });
  *handle = r.handle;
  return ret;
}

USHORT sl064_clear_configuration(UCHAR micro_slot) {
  return simple(micro_slot, SlcanOp::clear_configuration);
}

USHORT sl064_start_com(UCHAR micro_slot) {
  return simple(micro_slot, SlcanOp::start_com);
}

USHORT sl064_stop_com(UCHAR micro_slot) {
  return simple(micro_slot, SlcanOp::stop_com);
}

USHORT sl064_get_diagnosis(UCHAR micro_slot) {
  return Library::get().diagnosis(micro_slot);
}

USHORT sl064_set_data(UCHAR micro_slot, SL064Handle handle, UCHAR* data, UCHAR size) {
  if (data == nullptr && size > 0) {
    return SL064_E_DRIVER;
  }
  SlcanReply r{};
  return Library::get().op(micro_slot, SlcanOp::set_data, r, [&](SlcanRequest& m) {
    m.handle = handle;
    // More than 8 bytes: the driver refuses the call (2Ah); 9 stands for all of them.
    m.size = size > 8 ? 9 : size;
    if (size > 0) {
      std::memcpy(m.data, data, size > 8 ? 8 : size);
    }
  });
}

USHORT sl064_get_data(UCHAR micro_slot, SL064Handle handle, UCHAR* data_var, UCHAR* size_var) {
  if (data_var == nullptr || size_var == nullptr) {
    return SL064_E_DRIVER;
  }
  SlcanReply r{};
  const UCHAR wanted = *size_var;
  const USHORT ret = Library::get().op(micro_slot, SlcanOp::get_data, r, [&](SlcanRequest& m) {
    m.handle = handle;
    m.size = wanted;
  });
  *size_var = r.size;
  std::memcpy(data_var, r.data, r.size > 8 ? 8 : r.size);
  return ret;
}

USHORT sl064_send_data(UCHAR micro_slot, SL064Handle handle) {
  return simple(micro_slot, SlcanOp::send_data, handle);
}

USHORT sl064_send_data_request(UCHAR micro_slot, SL064Handle handle) {
  return simple(micro_slot, SlcanOp::send_data_request, handle);
}

USHORT sl064_clear_msg(UCHAR micro_slot, SL064Handle handle) {
  return simple(micro_slot, SlcanOp::clear_msg, handle);
}

USHORT sl064_set_acceptance_mask(UCHAR micro_slot, ULONG* mask, USHORT usage, USHORT serv_task,
                                 USHORT serv_func) {
  if (mask == nullptr) {
    return SL064_E_DRIVER;
  }
  SlcanReply r{};
  const USHORT ret =
      Library::get().op(micro_slot, SlcanOp::set_acceptance_mask, r, [&](SlcanRequest& m) {
        m.value = *mask;
        m.flags = usage;
        m.task = serv_task;
        m.func = serv_func;
      });
  if (ret == 0) {
    *mask = r.value;  // on error the mask stays as it was
  }
  return ret;
}

USHORT sl064_get_id(UCHAR micro_slot, SL064Handle handle, ULONG* id_var) {
  SlcanReply r{};
  const USHORT ret = Library::get().op(micro_slot, SlcanOp::get_id, r, [&](SlcanRequest& m) {
    m.handle = handle;
    if (handle == 0 && canemu::client::sl64::t_call_slot == micro_slot) {
      m.flags = canemu::ipc::kSlcanGetIdOfCall;  // the frame this routine was called for
      m.value = canemu::client::sl64::t_call_id;
    }
  });
  if (id_var != nullptr && ret == 0) {
    *id_var = r.value;
  }
  return id_var == nullptr ? USHORT{SL064_E_DRIVER} : ret;
}

USHORT sl064_get_msg_count(UCHAR micro_slot, SL064Handle handle, ULONG* count) {
  SlcanReply r{};
  const USHORT ret = Library::get().op(micro_slot, SlcanOp::get_msg_count, r,
                                       [&](SlcanRequest& m) { m.handle = handle; });
  if (count != nullptr && ret == 0) {
    *count = r.value;
  }
  return count == nullptr ? USHORT{SL064_E_DRIVER} : ret;
}

void sl064_set_led(UCHAR micro_slot, UCHAR data) {
  SlcanReply r{};
  (void)Library::get().op(micro_slot, SlcanOp::set_led, r,
                          [&](SlcanRequest& m) { m.value = data; });
}

UCHAR sl064_get_dout(UCHAR micro_slot) {
  SlcanReply r{};
  (void)Library::get().op(micro_slot, SlcanOp::get_led, r);
  return static_cast<UCHAR>(r.value);
}

UCHAR sl064_get_led(UCHAR micro_slot) {
  return sl064_get_dout(micro_slot);
}

USHORT sl064_evaluate_srq(UCHAR* micro_slot, SL064Handle* handle) {
  if (micro_slot == nullptr || handle == nullptr) {
    return SL064_E_DRIVER;
  }
  *handle = 0;
  SlcanReply r{};
  // The slot whose SRQ this is: the one asked, else the first held slot with a cause waiting.
  for (UCHAR s = 0; s < SL064_SLOTS; ++s) {
    if (!Library::get().holds(s)) {
      continue;
    }
    if (Library::get().op(s, SlcanOp::evaluate_srq, r) == 0 && (r.ret != 0 || r.handle != 0)) {
      *micro_slot = s;
      *handle = r.handle;
      return r.ret;
    }
  }
  return 0;  // «kein SRQ vom Treiberprogramm gesendet»
}

void sl064_enable_int_mask(UCHAR micro_slot) {
  (void)simple(micro_slot, SlcanOp::enable_int_mask);
}

void sl064_end_of_srq(UCHAR micro_slot) {
  (void)simple(micro_slot, SlcanOp::end_of_srq);
}

USHORT canemu_sl064_install_message_service(USHORT task, USHORT func, SL064MessageService routine) {
  return Library::get().install(task, func, reinterpret_cast<void*>(routine), false);
}

USHORT canemu_sl064_install_error_service(USHORT task, USHORT func, SL064ErrorService routine) {
  return Library::get().install(task, func, reinterpret_cast<void*>(routine), true);
}

USHORT canemu_sl064_driver_task(UCHAR micro_slot) {
  return static_cast<USHORT>(0x40 + micro_slot);
}

USHORT canemu_sl064_wait_srq(int timeout_ms) {
  return Library::get().wait_srq(timeout_ms);
}

USHORT canemu_sl064_eeprom_read(UCHAR micro_slot, USHORT word, USHORT* value) {
  if (value == nullptr || word >= 64) {
    return SL064_E_DRIVER;
  }
  SlcanReply r{};
  const USHORT ret = Library::get().op(micro_slot, SlcanOp::eeprom_read, r);
  if (ret == 0) {
    *value = r.eeprom[word];
  }
  return ret;
}

USHORT canemu_sl064_eeprom_write(UCHAR micro_slot, USHORT word, USHORT value) {
  SlcanReply r{};
  return Library::get().op(micro_slot, SlcanOp::eeprom_write, r, [&](SlcanRequest& m) {
    m.value = word;
    m.handle = value;
  });
}

ULONG canemu_sl064_lost_calls(UCHAR micro_slot) {
  return Library::get().lost_calls(micro_slot);
}

USHORT canemu_sl064_connect(const char* socket) {
  return Library::get().connect(socket);
}

}  // extern "C"
