// Every scalar parameter of the base model, addressed by its params-v1 dotted
// path, with unit, documentation and the physically allowed range.
//
// One table serves loading, saving, validation and (later) fit specs, so that
// adding a parameter is one row here and one field in parameters.h.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct ValueRange {
  double min = 0;
  bool min_inclusive = true;
  double max = 0;
  bool max_inclusive = true;

  bool Contains(double value) const;
  std::string Describe() const;  // e.g. "in (0, 1]"
};

struct ScalarParameterInfo {
  const char* path;  // "friction.positive.Fs"
  const char* unit;  // "N"
  const char* doc;
  ValueRange range;
  double& (*ref)(Parameters&);
  double (*get)(const Parameters&);
};

const std::vector<ScalarParameterInfo>& ScalarParameterTable();

// nullptr when no such scalar exists.
const ScalarParameterInfo* FindScalarParameter(const std::string& path);

// Reads a scalar by path, including effect parameters ("effects.valve_lag.tau").
// Returns false when the path names nothing in `params`.
bool GetParameter(const Parameters& params, const std::string& path, double* value);

// Writes a scalar by path, including effect parameters of effects present.
bool SetParameter(Parameters* params, const std::string& path, double value);

// Whether two sets hold the same model: every scalar of the table, the
// effects and their values, compared with == (so -0 and +0 alike, a NaN
// apart from everything), the modes (orientation, valve branch, pipeline
// model) and the delta(L) list. The name, uncertainty and provenance are not
// the model and are not compared. A field added to Parameters that is not a
// scalar of the table must be added there too: a static_assert on the
// struct's size says so.
bool SameValues(const Parameters& a, const Parameters& b);

}  // namespace pneumaid
