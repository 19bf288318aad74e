#include "canemu/daemon/world/lin_nodes.hpp"

#include <algorithm>

namespace canemu::daemon {

namespace lin = model::lin;

namespace {

lin::ScheduleTable table_of(const LinScheduleConfig& s) {
  lin::ScheduleTable t;
  t.name = s.name;
  for (const LinSlotConfig& c : s.slots) {
    lin::ScheduleSlot slot;
    switch (c.kind) {
      case LinSlotConfig::Kind::unconditional:
        slot.kind = lin::ScheduleSlot::Kind::unconditional;
        break;
      case LinSlotConfig::Kind::event_triggered:
        slot.kind = lin::ScheduleSlot::Kind::event_triggered;
        break;
      case LinSlotConfig::Kind::sporadic:
        slot.kind = lin::ScheduleSlot::Kind::sporadic;
        break;
    }
    slot.id = c.id;
    slot.frames = c.frames;
    slot.delay = model::SimDuration(c.delay_ns);
    t.slots.push_back(std::move(slot));
  }
  return t;
}

}  // namespace

SimulatedLinNode make_lin_node(const LinNodeConfig& config, std::size_t bus_index, lin::LinBus& bus,
                               uint32_t bus_bitrate) {
  auto ecu = std::make_unique<lin::LinEcu>(bus, config.bitrate != 0 ? config.bitrate : bus_bitrate);
  ecu->set_recording(false);  // it runs as long as canemud: counters only
  for (const LinResponseConfig& r : config.responses) {
    lin::Response response;
    response.size = static_cast<uint8_t>(std::min<std::size_t>(r.data.size(), lin::kMaxData));
    std::copy_n(r.data.begin(), response.size, response.data.begin());
    response.checksum = r.enhanced ? lin::Checksum::enhanced : lin::Checksum::classic;
    ecu->set_response(r.id, response);
    if (r.event_triggered) {
      ecu->add_event_triggered(*r.event_triggered, r.id);
    }
  }
  for (const LinScheduleConfig& s : config.schedules) {
    ecu->add_schedule(table_of(s));
  }
  if (!config.schedule.empty()) {
    ecu->run_schedule(config.schedule);
  }
  ecu->set_powered(config.powered);
  return SimulatedLinNode{config.name, bus_index, std::move(ecu)};
}

}  // namespace canemu::daemon
