// sgdicp: command-line registration of point clouds with SGD-ICP.
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.hpp"
#include "help_layout.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "sgdicp: register 3D point clouds with SGD-ICP (ICP solved by stochastic gradient descent "
      "on mini-batches; Maken, Ramos, Ott, ICRA 2019)."};
  sgdicp::cli::take_help_all(argc, argv);
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("sgdicp ") + sgdicp::kVersion);
  sgdicp::cli::add_register_command(app);
  sgdicp::cli::add_bench_command(app);
  sgdicp::cli::add_odometry_command(app);
  sgdicp::cli::add_localize_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    const int status = app.exit(e);
    const std::string hints = sgdicp::cli::unknown_option_hints(app);
    if (!hints.empty()) std::cerr << hints << '\n';
    return status;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const sgdicp::cli::ExitStatus& e) {
    std::cerr << "sgdicp: " << e.what() << '\n';
    return e.code();
  } catch (const sgdicp::Error& e) {
    std::cerr << "sgdicp: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "sgdicp: unexpected error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
