// Diagnose's reports: Markdown (the evidence), a terminal summary and the
// pneumaid-report/1 JSON.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "../io/yaml_reader.h"
#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/json.h"

namespace pneumaid {
namespace {

// A channel's value in display units: mm, bar, g/s.
double Display(const std::string& channel, double si) {
  if (channel == "x") return si * 1e3;
  if (channel[0] == 'p') return si * 1e-5;
  return si * 1e3;
}

const char* DisplayUnit(const std::string& channel) {
  if (channel == "x") return "mm";
  if (channel[0] == 'p') return "bar";
  return "g/s";
}

std::string Format(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char line[256];
  std::snprintf(line, sizeof(line), format, a, b, c, d);
  return line;
}

std::string RmseTable(const std::map<std::string, double>& before,
                      const std::map<std::string, double>& after) {
  std::ostringstream out;
  out << "| channel | RMSE before | RMSE after | change |\n|---|---|---|---|\n";
  for (const auto& [channel, a] : before) {
    const auto found = after.find(channel);
    out << "| " << channel << " | " << Format("%.4g", Display(channel, a)) << " "
        << DisplayUnit(channel) << " | ";
    if (found == after.end()) {
      out << "- | - |\n";
      continue;
    }
    out << Format("%.4g", Display(channel, found->second)) << " " << DisplayUnit(channel) << " | "
        << Format("%+.1f %%", 100 * (found->second / a - 1)) << " |\n";
  }
  return out.str();
}

}  // namespace

std::string DiagnoseResult::MarkdownReport() const {
  std::ostringstream out;
  out << "# Diagnose: " << (before.unit.empty() ? std::string("unit") : before.unit) << "\n\n"
      << conclusion << "\n\n";
  for (std::size_t k = 0; k < iterations.size(); ++k) {
    const DiagnoseIteration& it = iterations[k];
    out << "## Iteration " << k + 1 << "\n\n### Where the model and the logs disagree\n\n";
    out << "| channel | regime | samples | RMSE | mean (measured - simulated) | reduced "
           "chi-square |\n|---|---|---|---|---|---|\n";
    for (const RegimeResidual& r : it.where.regimes) {
      out << "| " << r.channel << " | " << r.regime << " | " << r.samples << " | "
          << Format("%.4g", Display(r.channel, r.rmse)) << " " << DisplayUnit(r.channel) << " | "
          << Format("%+.4g", Display(r.channel, r.mean)) << " | "
          << (r.reduced_chi_square > 0 ? Format("%.3g", r.reduced_chi_square) : "-") << " |\n";
    }
    out << "\nWorst windows (RMSE relative to the channel's whole-run RMSE):\n\n";
    for (const ResidualWindow& w : it.where.worst) {
      out << "- " << w.run << " " << w.channel << " "
          << (Format("%.2f", w.from_s) != Format("%.2f", w.to_s)
                  ? Format("%.2f-%.2f s", w.from_s, w.to_s)
                  : Format("at %.2f s", w.from_s))  // one sample, or two 1 ms apart
          << Format(": RMSE %.4g", Display(w.channel, w.rmse)) << " " << DisplayUnit(w.channel)
          << Format(", mean %+.4g", Display(w.channel, w.mean)) << "\n";
    }
    if (it.ranking.empty()) {
      out << "\nNo candidates were fitted in this iteration.\n\n";
      continue;
    }
    out << "\n### Candidates (best first)\n\n| effect | held-back gain | worst fold | fitted-runs "
           "gain | in its channels | BIC change (reference only) | named | why |\n"
           "|---|---|---|---|---|---|---|---|\n";
    for (const CandidateScore& c : it.ranking) {
      out << "| " << c.effect << " | " << Format("%.1f %%", 100 * c.held_back_gain) << " | "
          << Format("%.1f %%", 100 * c.worst_fold_gain) << " | "
          << Format("%.1f %%", 100 * c.train_gain) << " | "
          << Format("%.0f %%", 100 * c.signature_share) << " | " << Format("%.4g", c.bic_change)
          << " | " << (c.effect == it.named ? "**yes**" : "no") << " | " << c.verdict << " |\n";
    }
    for (const CandidateScore& c : it.ranking) {
      if (c.effect != it.named) continue;
      out << "\n### Named: " << c.effect << "\n\nFitted on every run:\n\n```\n"
          << c.fit.CoefficientReport("") << "```\n\nHeld-back gain per channel:";
      for (const auto& [channel, gain] : c.channel_gain)
        out << " " << channel << Format(" %+.1f %%", 100 * gain);
      out << "\n\n";
      if (!c.moved_base.empty()) {
        out << "Base coefficients moved beyond the identification tolerances by adding it:\n\n";
        for (const std::string& m : c.moved_base) out << "- " << m << "\n";
        out << "\n";
      }
      out << RmseTable(it.rmse_before, it.rmse_after) << "\n";
    }
  }
  if (!named_effects.empty()) {
    out << "## Before and after, every run\n\n"
        << RmseTable(iterations.front().rmse_before, iterations.back().rmse_before) << "\n";
  }
  return out.str();
}

std::string DiagnoseResult::BriefReport() const {
  std::ostringstream out;
  out << "Diagnose: " << conclusion << "\n";
  for (std::size_t k = 0; k < iterations.size(); ++k) {
    const DiagnoseIteration& it = iterations[k];
    if (it.ranking.empty()) continue;
    out << "  iteration " << k + 1 << ":\n";
    for (const CandidateScore& c : it.ranking) {
      out << "    " << c.effect << ": " << c.verdict << (c.effect == it.named ? "  <- named" : "")
          << "\n";
    }
  }
  if (!named_effects.empty()) {
    out << "  RMSE before -> after:";
    for (const auto& [channel, a] : iterations.front().rmse_before) {
      const auto found = iterations.back().rmse_before.find(channel);
      if (found == iterations.back().rmse_before.end()) continue;
      out << " " << channel << " "
          << Format("%.4g -> %.4g", Display(channel, a), Display(channel, found->second)) << " "
          << DisplayUnit(channel) << ";";
    }
    out << "\n";
  }
  return out.str();
}

std::string DiagnoseToJson(const DiagnoseResult& result) {
  std::ostringstream out;
  const auto pooled = [&out](const std::map<std::string, double>& rmse) {
    out << "{";
    std::size_t k = 0;
    for (const auto& [channel, value] : rmse)
      out << (k++ ? ", " : "") << JsonString(channel) << ": {\"rmse\": " << JsonNumber(value)
          << "}";
    out << "}";
  };
  out << "{\"format\": \"pneumaid-report/1\", \"unit\": " << JsonString(result.after.unit)
      << ",\n \"experiments\": " << ExperimentsToJson(result.after) << ",\n \"named_effects\": [";
  for (std::size_t i = 0; i < result.named_effects.size(); ++i)
    out << (i ? ", " : "") << JsonString(result.named_effects[i]);
  out << "],\n \"before\": ";
  pooled(result.iterations.front().rmse_before);
  out << ",\n \"after\": ";
  pooled(result.iterations.back().rmse_before);
  out << ",\n \"conclusion\": " << JsonString(result.conclusion) << ",\n \"iterations\": [";
  for (std::size_t k = 0; k < result.iterations.size(); ++k) {
    const DiagnoseIteration& it = result.iterations[k];
    out << (k ? ",\n  " : "\n  ") << "{\"named\": " << JsonString(it.named) << ", \"ranking\": [";
    for (std::size_t c = 0; c < it.ranking.size(); ++c) {
      const CandidateScore& s = it.ranking[c];
      out << (c ? ", " : "") << "{\"effect\": " << JsonString(s.effect)
          << ", \"held_back_gain\": " << JsonNumber(s.held_back_gain)
          << ", \"own_channel_gain\": " << JsonNumber(s.own_channel_gain)
          << ", \"worst_fold_gain\": " << JsonNumber(s.worst_fold_gain) << ", \"fold_gains\": [";
      for (std::size_t f = 0; f < s.fold_gains.size(); ++f)
        out << (f ? ", " : "") << JsonNumber(s.fold_gains[f]);
      out << "]"
          << ", \"train_gain\": " << JsonNumber(s.train_gain)
          << ", \"signature_share\": " << JsonNumber(s.signature_share)
          << ", \"improved_share\": " << JsonNumber(s.improved_share)
          << ", \"bic_change\": " << JsonNumber(s.bic_change)
          << ", \"significant\": " << (s.significant ? "true" : "false")
          << ", \"verdict\": " << JsonString(s.verdict) << "}";
    }
    out << "]}";
  }
  out << "]}\n";
  return out.str();
}

namespace {

// JSON is YAML's flow style: the report is read back with the YAML readers'
// checks (syntax errors at their line and column).
class NamedEffectsReader : internal::YamlReader {
 public:
  explicit NamedEffectsReader(const std::string& path) : YamlReader(path) {}

  std::vector<std::string> Read(const std::string& text, const std::string& unit) const {
    return Guarded([&]() {
      const YAML::Node root = LoadMapping(text, "expected a pneumaid-report/1 JSON object");
      const YAML::Node format = root["format"];
      if (!format || Text(format) != "pneumaid-report/1")
        Fail(format ? format : root, "format: expected pneumaid-report/1");
      const YAML::Node named = root["named_effects"];
      if (!named || !named.IsSequence())
        Fail(named ? named : root, "named_effects: expected a list (a diagnose report)");
      const YAML::Node of = root["unit"];
      if (!of || Text(of) != unit) {
        Fail(of ? of : root, "unit: a diagnose report of " +
                                 (of ? "unit '" + Text(of) + "'" : std::string("no unit")) +
                                 ", expected one of unit '" + unit + "'");
      }
      std::vector<std::string> effects;
      for (const auto& effect : named) effects.push_back(Text(effect));
      return effects;
    });
  }
};

}  // namespace

std::vector<std::string> ReadNamedEffects(const std::string& report_json_path,
                                          const std::string& unit) {
  return NamedEffectsReader(report_json_path)
      .Read(ReadTextFile(report_json_path, "a diagnose report (pneumaid-report/1 JSON)"), unit);
}

}  // namespace pneumaid
