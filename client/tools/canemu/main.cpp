// canemu: the command-line tool. status, fault and time talk to canemud over its control
// socket; send and dump open a channel on an ephemeral device; calc works offline on the wire
// model. One file per subcommand (command.hpp).
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.hpp"

int main(int argc, char** argv) {
  using namespace canemu::cli;
  CLI::App app{"canemu: talk to canemud, and calculate CAN frames and bit timings"};
  app.require_subcommand(1);
  std::string socket;
  app.add_option("--socket", socket, "canemud's control socket (default: $CANEMU_SOCKET, ...)");
  const std::vector<Command> commands = {add_status(app, socket), add_send(app, socket),
                                         add_dump(app, socket),   add_fault(app, socket),
                                         add_time(app, socket),   add_calc(app)};
  CLI11_PARSE(app, argc, argv);
  try {
    for (const Command& c : commands) {
      if (*c.app) {
        return c.run();
      }
    }
  } catch (const std::exception& e) {
    return fail(std::string("bad argument: ") + e.what());
  }
  return 1;
}
