#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/protocol.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid::cli {
namespace {

struct SynthArgs {
  std::string truth_path;
  std::string protocol_path;
  std::uint64_t seed = 1;
  std::string out_dir;
  std::string unit_id;
  std::vector<std::string> spread;  // "path=fraction"
  std::vector<std::string> scale;   // "path=factor"
};

const char* const kPathNumber = "PATH=NUMBER, e.g. valve.*.q_max=0.05";

int RunSynth(const SynthArgs& args) {
  Parameters truth = LoadParams(args.truth_path);
  const Protocol protocol = LoadProtocol(args.protocol_path);
  truth = ApplySpread(truth, ParseAssignments(args.spread, "--spread", kPathNumber), args.seed);
  const std::string unit_id = args.unit_id.empty() ? truth.unit : args.unit_id;
  SyntheticUnit unit;
  try {
    truth = ApplyScale(truth, ParseAssignments(args.scale, "--scale", kPathNumber));
    unit = Synthesize(truth, protocol, args.seed, unit_id);
  } catch (const InputError& error) {
    // The library names its objects; here they are flags.
    const std::string flag = error.file() == "scale" ? "--scale" : "--truth " + args.truth_path;
    throw InputError(flag, error.line(), 0, error.message());
  }
  WriteDirectoryAtomically(args.out_dir, UnitFiles(unit));
  std::cout << "wrote synthetic unit " << unit_id << " to " << args.out_dir << " ("
            << unit.logs.size() << " logs, seed " << args.seed << ")\n";
  return kSuccess;
}

}  // namespace

CommandRunner AddSynthCommand(CLI::App* app) {
  auto args = std::make_shared<SynthArgs>();
  app->add_option("--truth", args->truth_path, "truth parameter set (params-v1)")->required();
  app->add_option("--protocol", args->protocol_path, "test protocol (pneumaid-protocol/1)")
      ->required();
  app->add_option("--seed", args->seed, "random seed (noise, spread)")->capture_default_str();
  app->add_option("--out", args->out_dir, "new unit directory (must not exist or be empty)")
      ->required();
  app->add_option("--unit", args->unit_id, "unit id (default: the truth's unit)");
  app->add_option("--spread", args->spread,
                  "manufacturing spread PATH=FRACTION: multiply by 1 + U(-f, f) ('*' matches "
                  "one path segment; repeatable)");
  app->add_option("--scale", args->scale, "multiply PATH by FACTOR (an outlier; repeatable)");
  return [args]() { return RunSynth(*args); };
}

}  // namespace pneumaid::cli
