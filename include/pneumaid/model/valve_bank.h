// Four proportional valves used as one bidirectional servovalve.
//
// u > 0 opens supply -> chamber 1 and chamber 2 -> exhaust with opening |u|;
// u < 0 opens chamber 1 -> exhaust and supply -> chamber 2.
#pragma once

#include <array>
#include <cmath>

namespace pneumaid {

enum ValveIndex : int {
  kSupplyToChamber1 = 0,
  kChamber1ToExhaust = 1,
  kSupplyToChamber2 = 2,
  kChamber2ToExhaust = 3,
  kValveCount = 4,
};

using ValveOpenings = std::array<double, kValveCount>;

// The two valves a command opens together: u > 0 opens supply -> 1 and
// 2 -> exhaust, u < 0 opens 1 -> exhaust and supply -> 2. The two always see
// the same opening and the same K_vp branch, so a lag on their openings or
// conductances needs one state per pair, not per valve (an effect that set
// the two apart would need a state each again).
struct ValvePair {
  ValveIndex lead, partner;
};
inline constexpr int kValvePairCount = 2;
inline constexpr std::array<ValvePair, kValvePairCount> kValvePairs = {
    {{kSupplyToChamber1, kChamber2ToExhaust}, {kChamber1ToExhaust, kSupplyToChamber2}}};

// Openings [V] of the four valves for a bidirectional command u [V].
// |u| is clamped to 1, the end of the command range.
inline ValveOpenings OpeningsForCommand(double command_V) {
  const double opening = std::fmin(std::fabs(command_V), 1.0);
  ValveOpenings out{0, 0, 0, 0};
  if (command_V > 0) {
    out[kSupplyToChamber1] = opening;
    out[kChamber2ToExhaust] = opening;
  } else if (command_V < 0) {
    out[kChamber1ToExhaust] = opening;
    out[kSupplyToChamber2] = opening;
  }
  return out;
}

// Which K_vp branch one valve follows in hysteresis mode. The branch follows
// the direction of the last change of the opening larger than `threshold`,
// measured from the opening where it was last latched: a held command with
// noise below threshold/2 never switches, a slow ramp re-latches every
// `threshold` and a reversal switches within 2 x threshold of the turning point.
class BranchLatch {
 public:
  explicit BranchLatch(double threshold_V, double initial_opening_V = 0.0)
      : threshold_V_(threshold_V), reference_V_(initial_opening_V) {}

  void Update(double opening_V) {
    if (opening_V > reference_V_ + threshold_V_) {
      decreasing_ = false;
      reference_V_ = opening_V;
    } else if (opening_V < reference_V_ - threshold_V_) {
      decreasing_ = true;
      reference_V_ = opening_V;
    }
  }

  bool decreasing() const { return decreasing_; }

 private:
  double threshold_V_;
  double reference_V_;
  bool decreasing_ = false;
};

}  // namespace pneumaid
