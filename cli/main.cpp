// polyheal — exact-arithmetic polyhedral repair. Dispatch only.
#include <cstdio>
#include <exception>

#include "commands.h"
#include "polyheal/mesh/errors.h"

int main(int argc, char** argv) {
  using namespace polyheal::cli;
  CLI::App app{
      "polyheal: exact-arithmetic repair and certification of triangle meshes.\n"
      "Every claim about a mesh is decided by exact predicates on its own coordinates.\n"
      "Exit codes: 0 certified clean, 1 defects remain, 2 error."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "polyheal 0.1.0");
  int exit_code = kError;
  add_repair(app, exit_code);
  add_check(app, exit_code);
  add_compare(app, exit_code);
  add_batch(app, exit_code);
  add_perturb(app, exit_code);
  add_degenerate(app, exit_code);
  add_deintersect(app, exit_code);
  add_regularize(app, exit_code);
  add_offset(app, exit_code);
  add_union(app, exit_code);
  add_rebuild(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "polyheal: error: %s\n", e.what());
    return kError;
  } catch (...) {
    std::fprintf(stderr, "polyheal: error: unknown failure\n");
    return kError;
  }
  return exit_code;
}
