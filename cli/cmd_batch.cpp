// polyheal batch LIST -o DIR — `polyheal repair` over many files, each in its
// own process (so a crash, a time-out or a memory limit stops one file, not
// the batch), N at a time, with a CSV and JSON summary.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"

namespace polyheal::cli {
namespace {

namespace fs = std::filesystem;

struct BatchArgs {
  std::string list, dir, shard, format = "off";
  int jobs = 1;
  double timeout = 600;     // seconds per file
  double memory_mb = 8192;  // address-space limit per file
  std::vector<std::string> repair_args;  // passed through to each repair
  bool json = false, overwrite = false;
};

struct Job {
  std::string input, output, report;  // report: the repair's --json document
  pid_t pid = -1;
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;
  // results
  std::string status;  // certified | defects | error | timeout | out-of-memory | crashed
  int exit_code = -1;
  double seconds = 0, peak_mb = 0;
  nlohmann::json summary = nlohmann::json::object();
  std::string error;
};

/// The inputs: LIST is a directory (its mesh files, sorted) or a text file
/// with one path per line (blank lines and lines starting with # skipped;
/// relative paths are relative to the working directory, as on a command line).
std::vector<std::string> read_list(const std::string& list) {
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_directory(list, ec)) {
    for (const auto& e : fs::directory_iterator(list)) {
      if (!e.is_regular_file()) continue;
      try {
        format_from_path(e.path().string());
        files.push_back(e.path().string());
      } catch (const InputError&) {
      }
    }
    std::sort(files.begin(), files.end());
    return files;
  }
  std::ifstream in(list);
  if (!in) throw InputError(list, "", "cannot open the list for reading");
  std::string line;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    std::size_t s = line.find_first_not_of(" \t");
    if (s == std::string::npos || line[s] == '#') continue;
    files.push_back(line.substr(s));
  }
  return files;
}

/// --shard K/N: the files whose position (0-based, in list order) is K-1
/// modulo N. Deterministic: every machine of an array job reads the same
/// list and takes a disjoint slice; together they cover it.
std::vector<std::string> shard(const std::vector<std::string>& files, const std::string& spec) {
  if (spec.empty()) return files;
  int k = 0, n = 0;
  char slash = 0, extra = 0;
  std::istringstream in(spec);
  if (!(in >> k >> slash >> n) || slash != '/' || (in >> extra) || n < 1 || k < 1 || k > n)
    throw CLI::ValidationError("--shard", "expected K/N with 1 <= K <= N: " + spec);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < files.size(); ++i)
    if (int(i % std::size_t(n)) == k - 1) out.push_back(files[i]);
  return out;
}

/// Output names: DIR/<stem>.<format>; stems that repeat get -2, -3, ...
void name_outputs(std::vector<Job>& jobs, const BatchArgs& a) {
  std::map<std::string, int> seen;
  for (Job& j : jobs) {
    std::string stem = fs::path(j.input).stem().string();
    const int n = ++seen[stem];
    if (n > 1) stem += "-" + std::to_string(n);
    j.output = (fs::path(a.dir) / (stem + "." + a.format)).string();
    j.report = (fs::path(a.dir) / (stem + ".report.json")).string();
  }
}

void start(Job& j, const BatchArgs& a, const std::string& self) {
  std::vector<std::string> argv = {self, "repair", j.input, "-o", j.output, "--json"};
  if (a.overwrite) argv.push_back("--overwrite");
  argv.insert(argv.end(), a.repair_args.begin(), a.repair_args.end());
  j.start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("cannot start a process: ") + std::strerror(errno));
  if (pid == 0) {
    // Child: the report to its file, errors to its .err file, limits, exec.
    const int out = ::open(j.report.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open((j.report + ".err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0 || err < 0) _exit(125);
    dup2(out, 1);
    dup2(err, 2);
    rlimit mem{};
    mem.rlim_cur = mem.rlim_max = rlim_t(a.memory_mb * 1024 * 1024);
    setrlimit(RLIMIT_AS, &mem);
    std::vector<char*> cargv;
    for (std::string& s : argv) cargv.push_back(s.data());
    cargv.push_back(nullptr);
    execv(self.c_str(), cargv.data());
    _exit(127);
  }
  j.pid = pid;
}

void finish(Job& j, int status, const rusage& use) {
  j.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - j.start).count();
  j.peak_mb = double(use.ru_maxrss) / 1024.0;
  std::string err;
  {
    std::ifstream e(j.report + ".err");
    std::getline(e, err, '\0');
  }
  while (!err.empty() && err.back() == '\n') err.pop_back();
  if (j.timed_out) {
    j.status = "timeout";
  } else if (WIFSIGNALED(status)) {
    j.status = "crashed";
    j.error = std::string("signal ") + strsignal(WTERMSIG(status));
  } else {
    j.exit_code = WEXITSTATUS(status);
    if (j.exit_code == 0 || j.exit_code == 1) {
      j.status = j.exit_code == 0 ? "certified" : "defects";
      try {
        std::ifstream in(j.report);
        const nlohmann::json r = nlohmann::json::parse(in);
        j.summary = {{"defects_before", r["input_mesh"]["defects"]},
                     {"certified", r["certified"]},
                     {"problems", r["problems"]},
                     {"faces_in", r["input_mesh"]["faces"]},
                     {"faces_out", r["output_mesh"]["faces"]},
                     {"hausdorff", r["deviation"]["hausdorff"]},
                     {"hausdorff_relative", r["deviation"]["hausdorff_relative"]},
                     {"surface_moved", r["deviation"]["surface_moved"]},
                     {"defects_after", r["defects_after"]}};
      } catch (const std::exception& e) {
        j.status = "error";
        j.error = std::string("unreadable report: ") + e.what();
      }
    } else {
      j.status = err.find("bad_alloc") != std::string::npos || err.find("memory") != std::string::npos
                     ? "out-of-memory"
                     : "error";
      j.error = err.substr(err.rfind('\n') == std::string::npos ? 0 : err.rfind('\n') + 1);
    }
  }
  std::error_code ec;
  fs::remove(j.report + ".err", ec);
  if (j.status != "certified" && j.status != "defects") {
    // A run stopped after writing but before verifying leaves an output
    // nobody checked: remove it (the summary says what happened).
    if (j.status != "error") fs::remove(j.output, ec);
    if (fs::file_size(j.report, ec) == 0) fs::remove(j.report, ec);  // no report: the error says why
    if (!err.empty()) std::ofstream(j.report + ".err") << err << "\n";  // kept for the user
  }
}

std::string csv_field(std::string s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string number(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_number_float()) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v.get<double>());
    return b;
  }
  return v.dump();
}

void run(BatchArgs& a, int& exit_code) {
  std::vector<std::string> files = shard(read_list(a.list), a.shard);
  std::error_code ec;
  fs::create_directories(a.dir, ec);
  if (!fs::is_directory(a.dir)) throw OutputError(a.dir + ": cannot create the output directory");
  std::vector<Job> jobs(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) jobs[i].input = files[i];
  name_outputs(jobs, a);
  const std::string self = fs::read_symlink("/proc/self/exe", ec).string();
  if (self.empty()) throw std::runtime_error("cannot find the polyheal executable (/proc/self/exe)");
  const bool tty = isatty(2);

  std::size_t next = 0, done = 0;
  std::map<pid_t, std::size_t> running;
  while (done < jobs.size()) {
    while (running.size() < std::size_t(std::max(1, a.jobs)) && next < jobs.size()) {
      start(jobs[next], a, self);
      running[jobs[next].pid] = next;
      ++next;
    }
    int status = 0;
    rusage use{};
    const pid_t pid = wait4(-1, &status, WNOHANG, &use);
    if (pid > 0 && running.count(pid)) {
      Job& j = jobs[running[pid]];
      running.erase(pid);
      finish(j, status, use);
      ++done;
      if (tty)
        std::fprintf(stderr, "\r[%zu/%zu] %-10s %s\033[K", done, jobs.size(), j.status.c_str(), j.input.c_str());
      continue;
    }
    const auto now = std::chrono::steady_clock::now();
    for (auto& [p, i] : running)
      if (!jobs[i].timed_out && std::chrono::duration<double>(now - jobs[i].start).count() > a.timeout) {
        jobs[i].timed_out = true;
        kill(p, SIGKILL);
      }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (tty) std::fprintf(stderr, "\r\033[K");

  // Summary: CSV and JSON beside the outputs.
  std::ostringstream csv;
  csv << "input,output,status,exit_code,defects_before,defects_after,faces_in,faces_out,hausdorff,"
         "hausdorff_relative,surface_moved,seconds,peak_memory_mb,message\n";
  nlohmann::json rows = nlohmann::json::array();
  std::map<std::string, std::size_t> counts;
  for (const Job& j : jobs) {
    ++counts[j.status];
    auto field = [&](const char* k) { return j.summary.contains(k) ? number(j.summary[k]) : std::string(); };
    std::string message = j.error;
    if (message.empty() && j.summary.contains("problems"))
      for (const auto& p : j.summary["problems"]) message += (message.empty() ? "" : "; ") + p.get<std::string>();
    char t[64];
    std::snprintf(t, sizeof t, "%.3f,%.1f", j.seconds, j.peak_mb);
    csv << csv_field(j.input) << "," << csv_field(j.output) << "," << j.status << ","
        << (j.exit_code >= 0 ? std::to_string(j.exit_code) : "") << "," << field("defects_before") << ","
        << field("defects_after") << "," << field("faces_in") << "," << field("faces_out") << "," << field("hausdorff")
        << "," << field("hausdorff_relative") << "," << field("surface_moved") << "," << t << "," << csv_field(message)
        << "\n";
    nlohmann::json row = {{"input", j.input},     {"output", j.output},       {"report", j.report},
                          {"status", j.status},   {"exit_code", j.exit_code}, {"seconds", j.seconds},
                          {"peak_memory_mb", j.peak_mb}, {"message", message}};
    for (auto it = j.summary.begin(); it != j.summary.end(); ++it)
      if (it.key() != "problems") row[it.key()] = it.value();
    rows.push_back(row);
  }
  nlohmann::json doc = {{"schema", "polyheal.batch/1"},
                        {"list", a.list},
                        {"shard", a.shard.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.shard)},
                        {"files", jobs.size()},
                        {"counts", counts},
                        {"limits", {{"timeout_seconds", a.timeout}, {"memory_mb", a.memory_mb}}},
                        {"results", rows}};
  const std::string csv_path = (fs::path(a.dir) / "summary.csv").string();
  const std::string json_path = (fs::path(a.dir) / "summary.json").string();
  write_file_atomically(csv_path, csv.str(), true);
  write_file_atomically(json_path, doc.dump(2) + "\n", true);
  if (a.json) {
    std::cout << doc.dump(2) << "\n";
  } else {
    std::printf("%zu files: ", jobs.size());
    bool first = true;
    for (const auto& [s, n] : counts) {
      std::printf("%s%zu %s", first ? "" : ", ", n, s.c_str());
      first = false;
    }
    std::printf("\nsummary: %s, %s\n", csv_path.c_str(), json_path.c_str());
  }
  exit_code = counts["certified"] == jobs.size() ? kClean : kDefects;
}

}  // namespace

void add_batch(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<BatchArgs>();
  CLI::App* cmd = app.add_subcommand("batch", "Repair many files, each in its own process, with a CSV/JSON summary");
  cmd->footer(
      "Runs `polyheal repair` on every file of LIST (a directory, or a text file with one path\n"
      "per line), N at a time, each in its own process with a time and memory limit, and goes on\n"
      "past failures. Writes DIR/<name>.<format> and DIR/<name>.report.json per file, and\n"
      "DIR/summary.csv and DIR/summary.json: status (certified, defects, error, timeout,\n"
      "out-of-memory, crashed), defects before and after, Hausdorff distance, time, peak memory.\n\n"
      "--shard K/N takes the files at positions K-1, K-1+N, ... of the list: N machines given the\n"
      "same list and K = 1..N cover it exactly once (see README for a Slurm array example).\n"
      "Options after -- go to every repair (e.g. -- --max-deviation 0.5% --weld 1e-6).\n\n"
      "Exit 0 when every file came out certified within bounds, 1 otherwise, 2 on error.");
  cmd->add_option("LIST", a->list, "directory of meshes, or a text file with one mesh path per line")->required();
  cmd->add_option("-o,--output-dir", a->dir, "directory for the outputs, reports and summary")->required();
  cmd->add_option("-j,--jobs", a->jobs, "files repaired at once")->default_val(1)->check(CLI::Range(1, 1024));
  cmd->add_option("--timeout", a->timeout, "seconds per file before it is stopped")
      ->default_val(600)->check(CLI::PositiveNumber);
  cmd->add_option("--memory", a->memory_mb, "address-space limit per file, MB")
      ->default_val(8192)->check(CLI::PositiveNumber);
  cmd->add_option("--shard", a->shard, "K/N: this machine's deterministic slice of the list");
  cmd->add_option("--format", a->format, "output format: off, obj, ply, stl")
      ->default_val("off")->check(CLI::IsMember({"off", "obj", "ply", "stl"}));
  cmd->add_flag("--overwrite", a->overwrite, "replace outputs that exist from an earlier run");
  cmd->add_flag("--json", a->json, "print the summary document (schema polyheal.batch/1) on stdout");
  cmd->add_option("repair-options", a->repair_args, "after --: options for every repair");
  cmd->callback([a, &exit_code] { run(*a, exit_code); });
}

}  // namespace polyheal::cli
