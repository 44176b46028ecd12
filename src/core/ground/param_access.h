// Reading and writing a params struct through its parameter table (a *_params.def file): the
// tools' --set, the tests' checks and the listings share these, whichever node's table it is.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "ladar_perception/ground/param_table.h"

namespace ladar_perception {

template <typename T>
T paramFromDouble(double v) { return static_cast<T>(v); }
template <>
inline bool paramFromDouble<bool>(double v) { return v != 0.0; }

// One row of a table with the accessors of its field in P.
template <typename P>
struct ParamAccess {
  ParamInfo info;
  double (*get)(const P&);
  void (*set)(P*, double);
};

// The rows of a table for P: define LADAR_PARAM as LADAR_PARAM_ACCESS(P) and include the .def
// inside a braced initializer list of ParamAccess<P>.
#define LADAR_PARAM_ACCESS(P, type, member, name, def, lo, hi, unit, meaning)                   \
  ParamAccess<P>{ParamInfo{#name, #member, #type, static_cast<double>(def),                     \
                           static_cast<double>(lo), static_cast<double>(hi), unit, meaning},    \
                 [](const P& p) { return static_cast<double>(p.member); },                      \
                 [](P* p, double v) { p->member = paramFromDouble<type>(v); }},

template <typename P>
const ParamAccess<P>* findParam(const std::vector<ParamAccess<P>>& table, const std::string& key) {
  for (const ParamAccess<P>& row : table) {
    if (key == row.info.name || key == row.info.member) return &row;
  }
  return nullptr;
}

// Sets the row named `key` (its name or field path) when `value` lies in its range.
template <typename P>
bool setParam(const std::vector<ParamAccess<P>>& table, const char* what, P* params,
              const std::string& key, double value, std::string* error) {
  const ParamAccess<P>* row = findParam(table, key);
  if (!row) {
    if (error) *error = std::string("unknown ") + what + " parameter '" + key + "'";
    return false;
  }
  if (!(value >= row->info.min && value <= row->info.max)) {
    if (error) {
      std::ostringstream s;
      s << row->info.name << " must lie in [" << row->info.min << ", " << row->info.max << "]";
      *error = s.str();
    }
    return false;
  }
  row->set(params, value);
  return true;
}

template <typename P>
bool getParam(const std::vector<ParamAccess<P>>& table, const P& params, const std::string& key,
              double* value) {
  const ParamAccess<P>* row = findParam(table, key);
  if (!row) return false;
  *value = row->get(params);
  return true;
}

template <typename P>
std::vector<ParamInfo> paramInfos(const std::vector<ParamAccess<P>>& table) {
  std::vector<ParamInfo> out;
  for (const ParamAccess<P>& row : table) out.push_back(row.info);
  return out;
}

}  // namespace ladar_perception
