// A simulated LIN node that canemud runs itself (`[[lin_node]]`, docs/lin.md), so that a
// program under test can be the only real node on a bus: a responder with its response table
// (and LIN 2.x event-triggered answers), and, as commander, schedule tables run at their exact
// slot times (unconditional, event-triggered with collision resolution, sporadic slots).
//
// Decisions where LIN 2.x leaves an emulation free (docs/lin.md):
// - A slot's delay runs from the start of its header to the start of the next slot's header.
// - An event-triggered frame that collides (a bit or checksum error, or a frame that is not
//   whole) makes the commander poll the slot's associated unconditional frames, one per slot
//   with the event-triggered slot's delay, before the table goes on (the collision resolving
//   schedule of LIN 2.1, made from the table itself).
// - A responder answers an event-triggered header with an associated frame whose data changed
//   since that frame last went out whole; the first data byte carries that frame's protected
//   identifier, as LIN 2.x requires (the response table's first byte is replaced).
// - A sporadic slot sends the first of its frames whose data the commander changed since it
//   last went, as header and response of its own; with none changed the slot stays silent.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/lin_bus.hpp"

namespace canemu::model::lin {

struct ScheduleSlot {
  enum class Kind : uint8_t { unconditional, event_triggered, sporadic };
  Kind kind = Kind::unconditional;
  uint8_t id = 0;  // the header's identifier (not used by a sporadic slot)
  SimDuration delay = milliseconds(10);
  std::vector<uint8_t> frames;  // event-triggered: associated frames; sporadic: candidates
};

struct ScheduleTable {
  std::string name;
  std::vector<ScheduleSlot> slots;
};

struct EcuCounters {
  uint64_t headers = 0;     // headers sent as commander
  uint64_t responses = 0;   // responses sent (whole frames with this node's response)
  uint64_t frames = 0;      // whole frames seen
  uint64_t errors = 0;      // errors seen
  uint64_t collisions = 0;  // event-triggered slots resolved
};

class LinEcu final : public LinNode, private EventHandler {
 public:
  LinEcu(LinBus& bus, uint32_t bitrate);
  ~LinEcu() override;
  LinEcu(const LinEcu&) = delete;
  LinEcu& operator=(const LinEcu&) = delete;

  // --- as responder ---
  // The response for `id` from now on; a change of data marks it for event-triggered and
  // sporadic slots.
  void set_response(uint8_t id, const Response& response);
  void clear_response(uint8_t id);
  std::optional<Response> response(uint8_t id) const;
  // The event-triggered frame `et_id` may carry this node's frame `id`.
  void add_event_triggered(uint8_t et_id, uint8_t id);
  // Off: it answers nothing and runs no schedule (a node switched off).
  void set_powered(bool on);
  bool powered() const { return powered_; }

  // --- as commander ---
  void add_schedule(ScheduleTable table);
  // Starts `name` at its first slot now (the running one stops); false for an unknown name.
  bool run_schedule(const std::string& name);
  void stop_schedule();
  const std::string& running_schedule() const { return running_; }

  const EcuCounters& counters() const { return counters_; }
  // What it saw, kept while recording (on from the start; a node that runs for long, as in
  // canemud, turns it off and keeps only its counters).
  const std::vector<Event>& seen() const { return seen_; }
  void clear_seen() { seen_.clear(); }
  void set_recording(bool on) { recording_ = on; }
  LinNodeId node() const { return id_; }

  // LinNode
  std::optional<Response> respond(uint8_t id) override;
  void on_lin_event(const Event& e) override;
  uint32_t lin_bitrate() const override { return bitrate_; }

 private:
  void on_event(SimTime now, uint64_t tag) override;
  void slot(SimTime now);
  const ScheduleTable* table() const;

  LinBus& bus_;
  SimScheduler& scheduler_;
  LinNodeId id_;
  uint32_t bitrate_;
  bool powered_ = true;
  std::map<uint8_t, Response> responses_;
  std::map<uint8_t, bool> changed_;                    // data changed since last sent whole
  std::map<uint8_t, std::vector<uint8_t>> et_frames_;  // et_id -> this node's frames
  std::optional<uint8_t> et_answer_;                   // the frame answered in this ET slot
  std::map<std::string, ScheduleTable> schedules_;
  std::string running_;
  std::size_t next_slot_ = 0;
  std::vector<uint8_t> resolving_;  // associated frames still to poll after a collision
  SimDuration resolving_delay_;
  std::optional<uint8_t> et_pending_;    // the ET slot whose outcome is awaited
  std::vector<uint8_t> et_slot_frames_;  // its associated frames
  std::optional<EventId> timer_;
  std::vector<Event> seen_;
  bool recording_ = true;
  EcuCounters counters_;
};

}  // namespace canemu::model::lin
