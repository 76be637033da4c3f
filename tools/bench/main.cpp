// stride-bench: every Stride benchmark, named <algorithm>/<robot>.
//   stride-bench --benchmark_filter='rnea/.*' --benchmark_format=json
//   stride-bench --config FILE [--robots-dir DIR]... --benchmark_filter='config:'
// --config FILE (or STRIDE_BENCH_CONFIG=FILE in the environment) adds the controller benchmarks
// on any controller configuration: controller_tick/config:NAME,
// tick_parts/config:NAME/{derivatives,backward,forward} and reference_update/config:NAME, NAME
// being FILE's name without .yaml (the paths in FILE are relative to its folder, as stride-mpc
// reads them; the file is only read).
// --robots-dir DIR (repeatable): where its public robots are looked for, before
// build/robot_packages. Every other argument is Google Benchmark's (--help lists them).
// tools/bench/run.sh runs it with repetitions and prints the medians.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "tools/bench/controller_source.hpp"

namespace stride::bench {
void registerMultibodyBenchmarks();
void registerContactBenchmarks();
}  // namespace stride::bench

namespace {

const char* const kUsage =
    "stride-bench [--config FILE] [--robots-dir DIR]... [Google Benchmark's flags]\n"
    "  --config FILE      also benchmark the controller on FILE (or STRIDE_BENCH_CONFIG=FILE):\n"
    "                     controller_tick/config:NAME, tick_parts/config:NAME/{derivatives,\n"
    "                     backward,forward}, reference_update/config:NAME (NAME: FILE's name\n"
    "                     without .yaml); --benchmark_filter='config:' runs only those\n"
    "  --robots-dir DIR   where FILE's public robots are looked for (repeatable), before\n"
    "                     build/robot_packages\n";

// Takes `--flag VALUE` or `--flag=VALUE` at argv[i] into value (i moves past it). False when
// argv[i] is another argument; exits 2 when the value is missing.
bool takeOption(const char* flag, int argc, char** argv, int& i, std::string& value) {
  const std::string arg = argv[i], prefix = std::string(flag) + "=";
  if (arg.rfind(prefix, 0) == 0) {
    value = arg.substr(prefix.size());
  } else if (arg == flag) {
    if (i + 1 >= argc) {
      std::fprintf(stderr, "stride-bench: %s needs a value\n%s", flag, kUsage);
      std::exit(2);
    }
    value = argv[++i];
  } else {
    return false;
  }
  if (value.empty()) {
    std::fprintf(stderr, "stride-bench: %s needs a value\n%s", flag, kUsage);
    std::exit(2);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  // Our options out of argv before Google Benchmark sees it (it refuses what it does not know).
  stride::bench::ControllerSource source;
  if (const char* env = std::getenv("STRIDE_BENCH_CONFIG"); env && *env) source.path = env;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    std::string value;
    if (takeOption("--config", argc, argv, i, value)) {
      source.path = value;
    } else if (takeOption("--robots-dir", argc, argv, i, value)) {
      source.robots_dirs.push_back(value);
    } else {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") std::fputs(kUsage, stdout);
      argv[kept++] = argv[i];
    }
  }
  argv[kept] = nullptr;
  argc = kept;

  stride::bench::registerMultibodyBenchmarks();
  stride::bench::registerContactBenchmarks();
  if (!source.path.empty()) {
    if (!std::filesystem::is_regular_file(source.path)) {
      std::fprintf(stderr, "stride-bench: no configuration file '%s'\n", source.path.c_str());
      return 2;
    }
    std::string name = std::filesystem::path(source.path).filename().string();
    for (const char* ext : {".yaml", ".yml"})
      if (name.size() > std::string(ext).size() &&
          name.compare(name.size() - std::string(ext).size(), std::string::npos, ext) == 0)
        name.resize(name.size() - std::string(ext).size());
    name = "config:" + name;
    try {
      const stride::ControllerConfig config = stride::bench::loadController(source);
      stride::bench::registerControllerBenchmarks(source, name, config);
      stride::bench::registerReferenceBenchmark(source, name, config);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stride-bench: %s\n", e.what());
      return 2;
    }
    benchmark::AddCustomContext("stride_config",
                                std::filesystem::absolute(source.path).lexically_normal().string());
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
