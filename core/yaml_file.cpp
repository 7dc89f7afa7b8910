#include "core/yaml_file.h"

#include <map>

#include <fmt/format.h>

#include "core/error.h"
#include "core/input_file.h"

namespace segslam {
namespace {

// Bounds on the walk: aliases may nest a node in itself or repeat it exponentially often
// ("billion laughs"); no file segslam reads comes near either.
constexpr int kMaxDepth = 100;
constexpr long kMaxNodes = 1000000;

void CheckNoDuplicateKeys(const YAML::Node& node, const std::string& origin, int depth, long* nodes) {
  if (depth > kMaxDepth || ++*nodes > kMaxNodes) {
    throw Error(fmt::format("{}: line {}: nested deeper than {} levels or over {} nodes (aliases that repeat "
                            "themselves?)",
                            origin, node.Mark().line + 1, kMaxDepth, kMaxNodes));
  }
  if (node.IsSequence()) {
    for (const YAML::Node& item : node) CheckNoDuplicateKeys(item, origin, depth + 1, nodes);
    return;
  }
  if (!node.IsMap()) return;
  std::map<std::string, int> first_line;  // key -> line it first appears on (1-based)
  for (const auto& item : node) {
    const int line = item.first.Mark().line + 1;
    if (item.first.IsScalar()) {
      const auto [seen, inserted] = first_line.emplace(item.first.Scalar(), line);
      if (!inserted) {
        throw Error(fmt::format("{}: line {}: key '{}' appears twice in one mapping (first on line {})", origin,
                                line, PrintableText(item.first.Scalar()), seen->second));
      }
    }
    CheckNoDuplicateKeys(item.second, origin, depth + 1, nodes);
  }
}

}  // namespace

void CheckNoDuplicateKeys(const YAML::Node& node, const std::string& origin) {
  long nodes = 0;
  CheckNoDuplicateKeys(node, origin, 0, &nodes);
}

YAML::Node LoadYamlText(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw Error(fmt::format("{}: line {}: malformed YAML: {}", origin, e.mark.line + 1, e.msg));
  }
  CheckNoDuplicateKeys(root, origin);
  return root;
}

YAML::Node LoadYamlFile(const std::filesystem::path& path) { return LoadYamlText(ReadFileText(path), path.string()); }

}  // namespace segslam
