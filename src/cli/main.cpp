// pneumaid: parse the command line, run one workflow, map errors to the exit
// statuses of the params spec. No numerics here.
#include <iostream>
#include <map>

#include "commands.h"
#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/input_error.h"

int main(int argc, char** argv) {
  using namespace pneumaid::cli;
  CLI::App app{"pneumaid: identify pneumatic actuators from rig logs"};
  app.set_version_flag("--version", std::string(PNEUMAID_VERSION));
  app.require_subcommand(1);
  std::map<CLI::App*, CommandRunner> runners;
  CLI::App* simulate = app.add_subcommand("simulate", "simulate a parameter set for a command");
  runners[simulate] = AddSimulateCommand(simulate);
  CLI::App* check = app.add_subcommand("check", "validate unit directories without fitting");
  runners[check] = AddCheckCommand(check);
  CLI::App* identify = app.add_subcommand("identify", "fit a parameter set to a unit's logs");
  runners[identify] = AddIdentifyCommand(identify);
  CLI::App* refine = app.add_subcommand(
      "refine", "refit chosen parameters through the simulator on several experiments");
  runners[refine] = AddRefineCommand(refine);
  CLI::App* validate =
      app.add_subcommand("validate", "simulate a unit's validation runs and compare");
  runners[validate] = AddValidateCommand(validate);
  CLI::App* diagnose = app.add_subcommand(
      "diagnose",
      "find where a parameter set and a unit's logs disagree and which effect explains it");
  runners[diagnose] = AddDiagnoseCommand(diagnose);
  CLI::App* synth =
      app.add_subcommand("synth", "write a synthetic unit directory from a truth set");
  runners[synth] = AddSynthCommand(synth);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int status = app.exit(error);
    return status == 0 ? kSuccess : kBadInput;
  }
  try {
    for (const auto& [subcommand, run] : runners) {
      if (subcommand->parsed()) return run();
    }
  } catch (const pneumaid::InputError& error) {
    std::cerr << "error: " << error.what() << "\n";
    return kBadInput;
  } catch (const pneumaid::FitError& error) {
    std::cerr << "error: " << error.what() << " (nothing written)\n";
    return kNumericalFailure;
  } catch (const std::exception& error) {
    std::cerr << "internal error: " << error.what() << "\n";
    return kUnexpected;
  }
  return kUnexpected;
}
