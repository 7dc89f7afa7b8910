#include "harness/machine.h"

#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <thread>

namespace segslam::harness {

nlohmann::json MachineDescription() {
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) host[0] = '\0';
  std::string cpu_model;
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      const auto value = colon == std::string::npos ? std::string::npos : line.find_first_not_of(' ', colon + 1);
      if (value != std::string::npos) cpu_model = line.substr(value);
      break;
    }
  }
  return {{"hostname", host}, {"cpu_model", cpu_model}, {"cores", std::thread::hardware_concurrency()}};
}

std::string MachineLine(const nlohmann::json& machine) {
  if (!machine.is_object()) return "?";
  return fmt::format("{}, {}, {} cores", machine.value("hostname", std::string("?")),
                     machine.value("cpu_model", std::string("?")), machine.value("cores", 0u));
}

}  // namespace segslam::harness
