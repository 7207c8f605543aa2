// polyheal CLI — one register function per subcommand (cmd_<name>.cpp).
#pragma once

#include <CLI/CLI.hpp>

namespace polyheal::cli {

/// Exit codes shared by every command.
enum Exit : int { kClean = 0, kDefects = 1, kError = 2 };

/// Adds `check` to `app`; on run, stores the command's exit code in `exit_code`.
void add_check(CLI::App& app, int& exit_code);
/// Adds `degenerate` (Botsch & Kobbelt degenerate-face removal).
void add_degenerate(CLI::App& app, int& exit_code);

/// Adds `deintersect` (Yamakawa & Shimada self-intersection removal).
void add_deintersect(CLI::App& app, int& exit_code);

/// Adds `regularize` (Jung, Shin & Choi valid-region growing).
void add_regularize(CLI::App& app, int& exit_code);

/// Adds `offset` (raw offset, then regularization).
void add_offset(CLI::App& app, int& exit_code);

/// Adds `union` (Boolean union of closed meshes by regularization).
void add_union(CLI::App& app, int& exit_code);

/// Adds `rebuild` (Hu, Lee, Blacker & Zhu overlay-grid cleanup).
void add_rebuild(CLI::App& app, int& exit_code);

/// Adds `repair` (the automatic pipeline).
void add_repair(CLI::App& app, int& exit_code);

/// Adds `compare` (another tool's output against its input).
void add_compare(CLI::App& app, int& exit_code);

/// Adds `batch` (repair over many files, one process each).
void add_batch(CLI::App& app, int& exit_code);

/// Adds `perturb` (adversarial degenerate tessellations).
void add_perturb(CLI::App& app, int& exit_code);

}  // namespace polyheal::cli
