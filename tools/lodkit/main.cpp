// lodkit command-line tool. Exit codes: 0 ok, 1 bad usage, 2 bad input, 3 internal error.
#include <cstdio>
#include <exception>
#include <new>

#include "commands.h"
#include "lodkit/error.h"

int main(int argc, char** argv) {
  CLI::App app{"lodkit: level of detail for 3D meshes", "lodkit"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "lodkit 0.1.0");
  const lod::cli::Command commands[] = {lod::cli::register_info(app), lod::cli::register_convert(app),
                                        lod::cli::register_simplify(app), lod::cli::register_compare(app),
                                        lod::cli::register_lod(app), lod::cli::register_optimize(app),
                                        lod::cli::register_analyze(app), lod::cli::register_render(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 1;
  }
  try {
    for (const auto& command : commands)
      if (command.app->parsed()) return command.run();
    return 1;
  } catch (const lod::Error& e) {
    std::fprintf(stderr, "lodkit: error: %s\n", e.what());
    switch (e.category()) {
      case lod::ErrorCategory::bad_input: return 2;
      case lod::ErrorCategory::usage: return 1;
      default: return 3;
    }
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "lodkit: internal error: out of memory\n");
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit: internal error: %s\n", e.what());
    return 3;
  }
}
