// canemu: the command-line tool. status, fault and time talk to canemud over its control
// socket; send, dump and gen open a channel on an ephemeral device; calc works offline on the
// wire model. One file per subcommand (command.hpp).
//
// Exit codes: 0 success, 1 any failure (a bad argument, canemud unreachable, a refused request,
// frames not sent), as can-utils do; `--help` and `--version` exit 0.
#include <exception>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "command.hpp"

int main(int argc, char** argv) {
  using namespace canemu::cli;
  CLI::App app{"canemu: talk to canemud, and calculate CAN frames and bit timings"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "canemu " CANEMU_VERSION, "print canemu's version and exit");
  std::string socket;
  app.add_option("--socket", socket, "canemud's control socket (default: $CANEMU_SOCKET, ...)");
  app.add_option("--wait", g_connect_wait_s,
                 "seconds to wait for canemud to listen (default 0: fail at once)")
      ->check(CLI::Range(0.0, 3600.0));
  const std::vector<Command> commands = {add_status(app, socket),
                                         add_metrics(app, socket),
                                         add_timeline(app, socket),
                                         add_plot(app, socket),
                                         add_send(app, socket),
                                         add_gen(app, socket),
                                         add_dump(app, socket),
                                         add_record(app, socket),
                                         add_bridge(app, socket),
                                         add_fault(app, socket),
                                         add_time(app, socket),
                                         add_eeprom(app, socket),
                                         add_lin(app, socket),
                                         add_restbus(app, socket),
                                         add_signal(app, socket),
                                         add_web(app, socket),
                                         add_calc(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11's own exit codes (100+) are not ours: every bad argument is exit 1, with the
    // parser's sentence and a pointer to --help.
    std::string what = e.what();
    return fail(what + "\n(canemu --help, or canemu SUBCOMMAND --help, lists the arguments)");
  }
  try {
    for (const Command& c : commands) {
      if (*c.app) {
        return c.run();
      }
    }
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return 1;
}
