// The machine a result was measured on, for reports and benchmarks: figures taken on
// different CPUs are not comparable without it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace segslam::harness {

// Host name, CPU model (from /proc/cpuinfo) and cores.
nlohmann::json MachineDescription();

// "host, CPU model, N cores" of a MachineDescription(), "?" for what it lacks.
std::string MachineLine(const nlohmann::json& machine);

}  // namespace segslam::harness
