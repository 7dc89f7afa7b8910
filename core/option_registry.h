// Every tunable of an options struct declared once, with what a user needs to set it: its
// name, kind, range, unit and one line of help; its default is read from a default-made
// struct. From that one declaration come the NAME=VALUE parsing of --tracker, --refiner
// and a scenario's bench.tracker / bench.refiner, the range check of a whole struct,
// the listings of `segslam options`, and the effective values echoed in results files.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/option_assignment.h"

namespace segslam {

enum class OptionKind { kReal, kWholeNumber, kSwitch };

// An interval of allowed values; an open end excludes its bound.
struct OptionRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;
  bool Holds(double value) const {
    return (min_open ? value > min : value >= min) && (max_open ? value < max : value <= max);
  }
};
inline OptionRange Closed(double min, double max) { return {min, max, false, false}; }
inline OptionRange ClosedOpen(double min, double max) { return {min, max, false, true}; }
inline OptionRange OpenClosed(double min, double max) { return {min, max, true, false}; }
inline OptionRange AtLeast(double min) { return {min, std::numeric_limits<double>::infinity(), false, false}; }
inline OptionRange Above(double min) { return {min, std::numeric_limits<double>::infinity(), true, false}; }

// "[0, 1)", ">= 4", "> 0"; a switch is "0 or 1".
std::string DescribeOptionRange(const OptionRange& range, OptionKind kind);
// A value as written in listings and messages: whole numbers without a point.
std::string FormatOptionValue(double value);
// JSON of a value of `kind`: a number, a whole number, or true/false.
nlohmann::json OptionValueJson(double value, OptionKind kind);

template <typename Options>
struct OptionSpec {
  std::string name;  // as set, e.g. "orb.max_features"
  OptionKind kind = OptionKind::kReal;
  OptionRange range;
  std::string unit;  // "m", "px", "s", "deg", or "" for counts, ratios and switches
  std::string help;  // one line
  double (*get)(const Options&) = nullptr;
  void (*set)(Options*, double) = nullptr;
};

template <typename Options>
class OptionRegistry {
 public:
  // `what` names the options in messages, e.g. "tracker option". Every default must lie
  // in its range (checked here: a declaration that breaks it is a bug).
  OptionRegistry(std::string what, std::vector<OptionSpec<Options>> specs)
      : what_(std::move(what)), specs_(std::move(specs)) {
    std::sort(specs_.begin(), specs_.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    if (const std::string problem = Check(Options()); !problem.empty()) throw Error("default out of range: " + problem);
  }

  // Sets one option from "name=value". Throws segslam::Error naming the option on an
  // unknown name, a malformed value, or a value outside its range (with the range and
  // unit), leaving `options` as it was.
  void Set(Options* options, const std::string& assignment) const {
    const NumericAssignment parsed = ParseNumericAssignment(assignment, what_);
    const OptionSpec<Options>* spec = Find(parsed.name);
    if (spec == nullptr) ThrowUnknownOption(what_, parsed.name, Names());
    double value = parsed.value;
    if (spec->kind == OptionKind::kWholeNumber) value = WholeNumberValue(parsed, what_);
    if (spec->kind == OptionKind::kSwitch) value = ZeroOrOneValue(parsed, what_);
    if (!spec->range.Holds(value)) {
      throw Error(what_ + " " + spec->name + ": " + parsed.text + " is outside its range " + RangeText(*spec));
    }
    spec->set(options, value);
  }

  // Empty when every registered option of `options` lies in its range; else which does
  // not, as "<what> NAME = VALUE is outside its range RANGE".
  std::string Check(const Options& options) const {
    for (const OptionSpec<Options>& spec : specs_) {
      const double value = spec.get(options);
      if (!spec.range.Holds(value)) {
        return what_ + " " + spec.name + " = " + FormatOptionValue(value) + " is outside its range " + RangeText(spec);
      }
    }
    return "";
  }

  // The names Set accepts, sorted.
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const OptionSpec<Options>& spec : specs_) names.push_back(spec.name);
    return names;
  }

  // Every registered option's value: {"name": value, ...}.
  nlohmann::json ToJson(const Options& options) const {
    nlohmann::json json = nlohmann::json::object();
    for (const OptionSpec<Options>& spec : specs_) json[spec.name] = OptionValueJson(spec.get(options), spec.kind);
    return json;
  }

  // The NAME=VALUE assignments that turn the defaults into `options`.
  std::vector<std::string> Differences(const Options& options) const {
    const Options defaults;
    std::vector<std::string> changed;
    for (const OptionSpec<Options>& spec : specs_) {
      if (spec.get(options) != spec.get(defaults)) changed.push_back(spec.name + "=" + FormatOptionValue(spec.get(options)));
    }
    return changed;
  }

  const std::vector<OptionSpec<Options>>& specs() const { return specs_; }
  const std::string& what() const { return what_; }
  std::string RangeText(const OptionSpec<Options>& spec) const {
    const std::string range = DescribeOptionRange(spec.range, spec.kind);
    return spec.unit.empty() ? range : range + " " + spec.unit;
  }

 private:
  const OptionSpec<Options>* Find(const std::string& name) const {
    for (const OptionSpec<Options>& spec : specs_) {
      if (spec.name == name) return &spec;
    }
    return nullptr;
  }

  std::string what_;
  std::vector<OptionSpec<Options>> specs_;
};

// A float field reads back as the shortest decimal that gives it (0.8f as 0.8).
double ReportedValue(float value);
inline double ReportedValue(double value) { return value; }

// One entry of a registry, for a field reached as `options.FIELD` (FIELD may be nested:
// orb.max_features). KIND is kReal, kWholeNumber (int or enum) or kSwitch (bool).
#define SEGSLAM_OPTION_REAL(Options, FIELD, RANGE, UNIT, HELP)                                                 \
  ::segslam::OptionSpec<Options> {                                                                            \
    #FIELD, ::segslam::OptionKind::kReal, RANGE, UNIT, HELP,                                                  \
        [](const Options& o) { return ::segslam::ReportedValue(o.FIELD); },                                    \
        [](Options* o, double v) { o->FIELD = static_cast<decltype(o->FIELD)>(v); }                            \
  }
#define SEGSLAM_OPTION_WHOLE(Options, FIELD, RANGE, UNIT, HELP)                                                \
  ::segslam::OptionSpec<Options> {                                                                            \
    #FIELD, ::segslam::OptionKind::kWholeNumber, RANGE, UNIT, HELP,                                           \
        [](const Options& o) { return static_cast<double>(static_cast<long long>(o.FIELD)); },                 \
        [](Options* o, double v) { o->FIELD = static_cast<decltype(o->FIELD)>(static_cast<long long>(v)); }    \
  }
#define SEGSLAM_OPTION_SWITCH(Options, FIELD, HELP)                                                            \
  ::segslam::OptionSpec<Options> {                                                                            \
    #FIELD, ::segslam::OptionKind::kSwitch, ::segslam::Closed(0, 1), "", HELP,                                \
        [](const Options& o) { return o.FIELD ? 1.0 : 0.0; }, [](Options* o, double v) { o->FIELD = v != 0; } \
  }

}  // namespace segslam
