// What a valve log measures of K_vp(u): the plateaus of a held command (a
// staircase), or, for a command that is not held (a ramp, a sampled signal),
// K_vp on a grid of openings per branch. Both are read through the flow
// meter's declared lag by one linear least-squares solve per log; a
// staircase's, when the manifest declares none, through the lag its steps
// show.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "../util/golden_section.h"
#include "../util/median.h"
#include "held_levels.h"
#include "pneumaid/ident/valve_fit.h"
#include "pneumaid/model/orifice.h"
#include "pneumaid/model/valve_bank.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid {
namespace {

using Levels = std::vector<std::pair<std::size_t, std::size_t>>;

double Mean(const std::vector<double>& v, std::size_t begin, std::size_t end) {
  return std::accumulate(v.begin() + begin, v.begin() + end, 0.0) /
         static_cast<double>(end - begin);
}

// Is the command held (a staircase)? Each level's trend (its least-squares
// slope times its duration) must stay below half the level threshold: a
// ramp's level runs through the whole threshold, a held level's noise does
// not. At least `held_fraction` of the samples must lie in such levels.
bool HeldCommand(const std::vector<double>& t, const std::vector<double>& u, const Levels& levels,
                 const ValveFitOptions& options) {
  if (static_cast<int>(levels.size()) > options.max_levels) return false;
  std::size_t held = 0;
  for (const auto& [begin, end] : levels) {
    if (end - begin < 3) continue;
    const double t_mean = Mean(t, begin, end), u_mean = Mean(u, begin, end);
    double stt = 0, stu = 0;
    for (std::size_t i = begin; i < end; ++i) {
      stt += (t[i] - t_mean) * (t[i] - t_mean);
      stu += (t[i] - t_mean) * (u[i] - u_mean);
    }
    const double trend_V = stt > 0 ? std::fabs(stu / stt) * (t[end - 1] - t[begin]) : 0.0;
    if (trend_V < 0.5 * options.level_change_V) held += end - begin;
  }
  return static_cast<double>(held) >= options.held_fraction * static_cast<double>(u.size());
}

// The level flows of a staircase seen through a meter lag of `tau_s`: the
// reading is linear in them (one lagged indicator column per level), so all
// come from one least-squares solve over the `used` samples. The diagonal
// of (A'A)^-1 (the levels' variance factors) only when asked: the lag
// scan's 60-odd solves need the squares alone.
struct LevelSolve {
  Eigen::VectorXd flow;
  Eigen::VectorXd inverse_diagonal;  // of (A'A)^-1, when asked
  double squares = HUGE_VAL;
  std::size_t rows = 0;
};

LevelSolve SolveLevels(const std::vector<double>& t, const std::vector<double>& q,
                       const Levels& levels, const std::vector<char>& used, double tau_s,
                       bool with_inverse_diagonal = false) {
  const std::size_t n = t.size(), m = levels.size();
  // Each level's column, nonzero from its first sample until its lagged
  // tail has decayed below 1e-12: (first sample, values). The same
  // recursion as ApplyFirstOrderLag (eval/lag.h), its factors computed once.
  std::vector<double> keep(n, 0.0);
  if (tau_s > 0)
    for (std::size_t i = 1; i < n; ++i) keep[i] = std::exp(-(t[i] - t[i - 1]) / tau_s);
  std::vector<std::pair<std::size_t, std::vector<double>>> columns(m);
  for (std::size_t k = 0; k < m; ++k) {
    const auto [begin, end] = levels[k];
    std::vector<double>& c = columns[k].second;
    columns[k].first = begin;
    if (!(tau_s > 0)) {
      c.assign(end - begin, 1.0);
      continue;
    }
    double y = begin == 0 ? 1.0 : 0.0;  // settled for the first level's input
    c.push_back(y);
    for (std::size_t i = begin + 1; i < n; ++i) {
      const double input = i - 1 < end ? 1.0 : 0.0;
      y = keep[i] * y + (1.0 - keep[i]) * input;
      if (i >= end && y < 1e-12) break;
      c.push_back(y);
    }
  }
  const auto value = [&columns](std::size_t k, std::size_t i) {
    const auto& [first, c] = columns[k];
    return i >= first && i - first < c.size() ? c[i - first] : 0.0;
  };
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
  LevelSolve out;
  for (std::size_t i = 0; i < n; ++i) out.rows += used[i] != 0;
  for (std::size_t j = 0; j < m; ++j) {
    const auto& [first, c] = columns[j];
    for (std::size_t i = first; i < first + c.size(); ++i) {
      if (!used[i]) continue;
      rhs[j] += c[i - first] * q[i];
      for (std::size_t k = j; k < m && columns[k].first <= i; ++k)
        normal(j, k) += c[i - first] * value(k, i);
    }
  }
  normal.triangularView<Eigen::StrictlyLower>() = normal.transpose();
  const Eigen::LDLT<Eigen::MatrixXd> solver(normal);
  if (solver.info() != Eigen::Success) return out;
  out.flow = solver.solve(rhs);
  std::vector<double> fitted(n, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    const auto& [first, c] = columns[k];
    for (std::size_t i = 0; i < c.size(); ++i) fitted[first + i] += c[i] * out.flow[k];
  }
  out.squares = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (used[i]) out.squares += std::pow(fitted[i] - q[i], 2);
  }
  if (with_inverse_diagonal)
    out.inverse_diagonal = solver.solve(Eigen::MatrixXd::Identity(m, m)).diagonal();
  return out;
}

// A flow meter's lag the manifest does not declare, read off the staircase's
// steps: the lag whose solve leaves the least squares, on a grid from 1 ms to
// half the median hold (a factor 1.25 apart) refined by golden section. Kept
// (else 0) when it lowers the squares by more than 25 times the residual
// variance (a five-sigma improvement for one more unknown): an undeclared
// 30 ms meter read over holds of 60 ms left most of each step in its
// plateau, K_vp 4.9 % of q_max off.
double ReadMeterLag(const std::vector<double>& t, const std::vector<double>& q,
                    const Levels& levels, const std::vector<char>& used) {
  std::vector<double> holds;
  for (const auto& [begin, end] : levels) holds.push_back(t[end - 1] - t[begin]);
  const double longest_s = 0.5 * internal::Median(std::move(holds));
  const auto squares = [&](double tau_s) { return SolveLevels(t, q, levels, used, tau_s).squares; };
  const LevelSolve none = SolveLevels(t, q, levels, used, 0.0);
  std::vector<double> grid;
  for (double tau_s = 1e-3; tau_s <= longest_s; tau_s *= 1.25) grid.push_back(tau_s);
  if (grid.empty() || !std::isfinite(none.squares)) return 0.0;
  std::vector<double> cost(grid.size());
  for (std::size_t k = 0; k < grid.size(); ++k) cost[k] = squares(grid[k]);
  const std::size_t best = std::min_element(cost.begin(), cost.end()) - cost.begin();
  double low = best > 0 ? grid[best - 1] : 0.5 * grid[0];
  double high = best + 1 < grid.size() ? grid[best + 1] : grid[best];
  const internal::GoldenSectionMinimum refined = internal::GoldenSection(squares, low, high, 20);
  double tau_s = refined.x, at = refined.value;
  if (cost[best] < at) tau_s = grid[best], at = cost[best];
  const double dof = static_cast<double>(none.rows) - static_cast<double>(levels.size()) - 1;
  if (!(dof > 0) || !(none.squares - at > 25.0 * at / dof)) return 0.0;
  return tau_s;
}

// The plateaus of a staircase: the flow held per level, seen through the
// meter's lag (declared, or when `tau_s` is negative read off the steps,
// ReadMeterLag), all from one least-squares solve (SolveLevels). The first
// settle_fraction of each level is left out (a valve's own opening dynamics
// are not modelled); the meter's lag is, so short holds work.
void StaircasePlateaus(const Experiment& e, const Levels& levels,
                       const OrificeCoefficients<double>& orifice, double tau_s, const Unit& unit,
                       const ValveFitOptions& options, std::vector<ValvePlateau>* plateaus) {
  const auto &t = e.column("t"), &u = e.column("u"), &q = e.column("q");
  const auto &p_up = e.column("p_up"), &p_down = e.column("p_down");
  const std::size_t n = t.size(), m = levels.size();
  std::vector<char> used(n, 0);
  std::vector<int> used_per_level(m, 0);
  for (std::size_t k = 0; k < m; ++k) {
    const auto [begin, end] = levels[k];
    const double skip = options.settle_fraction * (t[end - 1] - t[begin]);
    for (std::size_t i = begin; i < end; ++i) {
      if (t[i] >= t[begin] + skip) used[i] = 1, ++used_per_level[k];
    }
  }
  const bool read_lag = tau_s < 0;
  if (read_lag) tau_s = ReadMeterLag(t, q, levels, used);
  const LevelSolve solve = SolveLevels(t, q, levels, used, tau_s, true);
  if (!std::isfinite(solve.squares)) return;
  const Eigen::VectorXd& flow = solve.flow;
  const Eigen::VectorXd& inverse_diagonal = solve.inverse_diagonal;
  const double squares = solve.squares;
  const std::size_t rows = solve.rows;
  // Undeclared: the solve's own residual spread, not NoiseOf's estimate from
  // the readings (io/channel_noise.h): a level's K_vp error then carries
  // whatever of the log the held levels do not model, not the noise alone.
  const double unknowns = static_cast<double>(m) + (read_lag && tau_s > 0 ? 1.0 : 0.0);
  const double q_sigma = unit.manifest.DeclaredSigma(
      "q", std::sqrt(squares / std::max<double>(1.0, static_cast<double>(rows) - unknowns)));
  double previous_u = 0.0;  // the level before, for the branch
  bool decreasing = false;
  for (std::size_t k = 0; k < m; ++k) {
    const auto [begin, end] = levels[k];
    const double level = Mean(u, begin, end);
    // A level within half the threshold of the one before (a held command
    // the logger's noise split) stays on its branch.
    if (std::fabs(level - previous_u) > 0.5 * options.level_change_V)
      decreasing = level < previous_u;
    previous_u = level;
    if (level <= 0) continue;  // a closed valve says nothing about K_vp
    if (used_per_level[k] < options.min_plateau_samples) continue;
    const std::size_t first = end - static_cast<std::size_t>(used_per_level[k]);
    const double up = Mean(p_up, first, end), down = Mean(p_down, first, end);
    // Eq. 4 per unit of K_vp at the plateau's pressures.
    const double per_kvp = orifice.flow_scale * up * FlowShape(down / up, orifice);
    ValvePlateau plateau;
    plateau.experiment = e.entry.id;
    plateau.u_V = level;
    plateau.decreasing = decreasing;
    plateau.kvp_kg_per_s = flow[k] / per_kvp;
    plateau.kvp_sigma =
        std::max(q_sigma * std::sqrt(std::max(inverse_diagonal[k], 0.0)), 1e-15) / per_kvp;
    plateau.samples = used_per_level[k];
    plateau.meter_lag_s = tau_s;
    plateau.meter_lag_read = read_lag;
    plateaus->push_back(plateau);
  }
}

// The nodes of one branch's K_vp for a command that is not held: every
// node_spacing_V from the first (K_vp(0) = 0 is implied), sorted. With a
// break at u_sat (> 0) K_vp may jump there: the node is doubled, its left
// limit ending the polynomial and its right one starting saturation. The
// grid nodes stay (a break on a grid node replaces it), so that breaks
// between grid nodes leave as many unknowns.
struct BranchNodes {
  std::vector<double> u_V;
  std::vector<char> right;  // at or above the break
  double break_V = 0;

  BranchNodes(double spacing_V, double break_V) : break_V(break_V) {
    const int grid = static_cast<int>(std::ceil(1.0 / spacing_V - 1e-9));
    bool doubled = !(break_V > 0);
    for (int k = 1; k <= grid; ++k) {
      const double node = std::min(1.0, k * spacing_V);
      if (!doubled && node >= break_V) {
        u_V.insert(u_V.end(), {break_V, break_V});
        right.insert(right.end(), {0, 1});
        doubled = true;
        if (node == break_V) continue;  // the break is this node
      }
      u_V.push_back(node);
      right.push_back(!(break_V > 0) ? 0 : node > break_V);
    }
  }

  // The (up to two) nodes whose hats hold `opening`, with their weights.
  void Hats(double opening, int* node, double* hat) const {
    node[0] = node[1] = -1;
    const bool upper = break_V > 0 && opening >= break_V;
    // The nodes of the opening's side: [first, last).
    const std::size_t split = std::find(right.begin(), right.end(), 1) - right.begin();
    const std::size_t first = upper ? split : 0, last = upper ? u_V.size() : split;
    if (first == last) return;
    const auto begin = u_V.begin() + first, end = u_V.begin() + last;
    const std::size_t above = std::upper_bound(begin, end, opening) - u_V.begin();
    if (above == last) {  // at or past the side's last node: it alone
      node[0] = static_cast<int>(last - 1);
      hat[0] = 1.0;
      return;
    }
    const double low = above == first ? (upper ? break_V : 0.0) : u_V[above - 1];
    const double w = (opening - low) / (u_V[above] - low);
    node[0] = static_cast<int>(above);
    hat[0] = w;
    if (above > first) {
      node[1] = static_cast<int>(above - 1);
      hat[1] = 1 - w;
    }
  }
};

// A command that is not held: K_vp of each branch is taken as linear between
// its nodes (BranchNodes), so the flow at each sample is linear in the nodes'
// K_vp (a hat function of the opening times Eq. 4 per unit of K_vp at the
// sample's pressures), lagged by the meter: one least-squares solve. Each
// sample's branch is latched as the model latches it. A node is reported
// with the half-width of its hat, so that the saturation search can leave
// out the nodes whose hat spans K_vp's jump; with breaks (the second pass, at
// the u_sat found) the nodes at a break are its one-sided limits.
void ContinuousNodes(const Experiment& e, const OrificeCoefficients<double>& orifice, double tau_s,
                     const Unit& unit, const ValveFitOptions& options, const KvpBreaks& breaks,
                     std::vector<ValvePlateau>* plateaus) {
  const auto &t = e.column("t"), &u = e.column("u"), &q = e.column("q");
  const auto &p_up = e.column("p_up"), &p_down = e.column("p_down");
  const std::size_t n = t.size();
  const double h = options.node_spacing_V;
  const BranchNodes branch[2] = {BranchNodes(h, breaks.increasing_V),
                                 BranchNodes(h, breaks.decreasing_V)};
  const int offset[2] = {0, static_cast<int>(branch[0].u_V.size())};
  const int nodes = offset[1] + static_cast<int>(branch[1].u_V.size());
  // Each sample's (up to two) hat contributions: column (the branch's offset
  // plus its node) and weight, the weight including Eq. 4 per unit of K_vp.
  struct Contribution {
    int column[2] = {-1, -1};
    double weight[2] = {0, 0};
  };
  std::vector<Contribution> x(n);
  std::vector<double> support(nodes, 0.0);
  BranchLatch latch(SimulationOptions{}.hysteresis_threshold_V);  // as the simulator latches
  const std::vector<double> as_set = internal::CommandAsSet(u);   // not its logged noise
  double scale = 0;
  for (std::size_t i = 0; i < n; ++i) {
    latch.Update(as_set[i]);
    const double opening = std::clamp(u[i], 0.0, 1.0);
    if (opening <= 0 || !(p_up[i] > 0)) continue;
    const double per_kvp = orifice.flow_scale * p_up[i] * FlowShape(p_down[i] / p_up[i], orifice);
    if (!(per_kvp > 0)) continue;  // no pressure drop: the sample says nothing of K_vp
    const int b = latch.decreasing() ? 1 : 0;
    int node[2];
    double hat[2];
    branch[b].Hats(opening, node, hat);
    for (int slot = 0; slot < 2; ++slot) {
      if (node[slot] < 0 || hat[slot] <= 0) continue;
      x[i].column[slot] = offset[b] + node[slot];
      x[i].weight[slot] = hat[slot] * per_kvp;
      support[offset[b] + node[slot]] += hat[slot];
    }
    scale = std::max(scale, per_kvp);
  }
  // Only nodes some sample reaches are unknowns.
  std::vector<int> index(nodes, -1);
  int m = 0;
  for (int c = 0; c < nodes; ++c) {
    if (support[c] > 0) index[c] = m++;
  }
  if (m == 0) return;
  // The meter's lag, exact for a flow held between samples, applied to each
  // column as a running state; a state that has decayed away leaves the set.
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m), state = Eigen::VectorXd::Zero(m);
  std::vector<int> active;
  double qq = 0;
  const auto add = [&](const Contribution& c, double factor) {
    for (int s = 0; s < 2; ++s) {
      if (c.column[s] < 0) continue;
      const int j = index[c.column[s]];
      if (state(j) == 0.0 && std::find(active.begin(), active.end(), j) == active.end())
        active.push_back(j);
      state(j) += factor * c.weight[s];
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (tau_s > 0 && i > 0) {
      const double keep = std::exp(-(t[i] - t[i - 1]) / tau_s);
      for (int j : active) state(j) *= keep;
      add(x[i - 1], 1 - keep);
    } else {
      for (int j : active) state(j) = 0.0;
      active.clear();
      add(x[i], 1.0);
    }
    active.erase(std::remove_if(active.begin(), active.end(),
                                [&](int j) {
                                  if (std::fabs(state(j)) >= 1e-12 * scale) return false;
                                  state(j) = 0.0;
                                  return true;
                                }),
                 active.end());
    for (int a : active) {
      rhs(a) += state(a) * q[i];
      for (int b : active) normal(a, b) += state(a) * state(b);
    }
    qq += q[i] * q[i];
  }
  const Eigen::LDLT<Eigen::MatrixXd> solver(normal);
  if (solver.info() != Eigen::Success) return;
  const Eigen::VectorXd kvp = solver.solve(rhs);
  const double squares = std::max(0.0, qq - 2 * kvp.dot(rhs) + kvp.dot(normal * kvp));
  // Undeclared: the solve's residual spread, as for the held levels above.
  const double q_sigma = unit.manifest.DeclaredSigma(
      "q", std::sqrt(squares / std::max(1.0, static_cast<double>(n) - m)));
  const Eigen::MatrixXd inverse = solver.solve(Eigen::MatrixXd::Identity(m, m));
  for (int c = 0; c < nodes; ++c) {
    const int j = index[c];
    if (j < 0 || support[c] < options.min_plateau_samples) continue;
    const int b = c >= offset[1] ? 1 : 0, k = c - offset[b];
    const BranchNodes& nodes_of = branch[b];
    ValvePlateau node;
    node.experiment = e.entry.id;
    // A break's left limit is read just below u_sat, where K_vp is the polynomial.
    node.u_V = nodes_of.u_V[k] == nodes_of.break_V && !nodes_of.right[k]
                   ? std::nextafter(nodes_of.break_V, 0.0)
                   : nodes_of.u_V[k];
    node.decreasing = b == 1;
    node.kvp_kg_per_s = kvp(j);
    node.kvp_sigma = std::max(q_sigma * std::sqrt(std::max(inverse(j, j), 0.0)), 1e-15);
    node.samples = static_cast<int>(std::lround(support[c]));
    node.meter_lag_s = tau_s;
    node.support_half_width_V = h;
    plateaus->push_back(node);
  }
}

}  // namespace

std::vector<ValvePlateau> ExtractValvePlateaus(const Unit& unit, double normalization,
                                               const ValveFitOptions& options,
                                               const KvpBreaks& breaks,
                                               const std::vector<ValvePlateau>* earlier) {
  const RigConstants& rig = unit.manifest.rig;
  const auto orifice =
      MakeOrificeCoefficients<double>(rig.gas.heat_capacity_ratio, rig.gas.gas_constant_J_per_kgK,
                                      rig.gas.temperature_K, normalization);
  const double tau = unit.manifest.DeclaredTau("q", -1.0);  // negative: not declared
  std::vector<ValvePlateau> plateaus;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kValve) continue;
    const auto& u = e.column("u");
    const auto levels = internal::HeldLevels(u, options.level_change_V);
    if (HeldCommand(e.column("t"), u, levels, options)) {
      if (earlier == nullptr) {
        StaircasePlateaus(e, levels, orifice, tau, unit, options, &plateaus);
        continue;
      }
      for (const ValvePlateau& p : *earlier) {
        if (p.experiment == e.entry.id && p.support_half_width_V == 0) plateaus.push_back(p);
      }
    } else {
      ContinuousNodes(e, orifice, std::max(tau, 0.0), unit, options, breaks, &plateaus);
    }
  }
  return plateaus;
}

}  // namespace pneumaid
