// Ground models by name (ground_segment --method, the nodelets' `method` parameter).
#include "ladar_perception/ground/ground_model.h"

#include "ladar_perception/ground/vertical_scan.h"

namespace ladar_perception {

std::vector<std::string> groundModelNames() {
  // The default first.
  return {"vertical_scan", "vertical_scan_thesis"};
}

std::unique_ptr<GroundModel> makeGroundModel(const std::string& name, std::string* error) {
  if (name == "vertical_scan" || name == "default") {
    return std::make_unique<VerticalScanGround>(verticalScanDefaultParams(), "vertical_scan");
  }
  if (name == "vertical_scan_thesis" || name == "thesis") {
    return std::make_unique<VerticalScanGround>(verticalScanThesisParams(),
                                                "vertical_scan_thesis");
  }
  if (error) {
    std::string list;
    for (const std::string& n : groundModelNames()) list += (list.empty() ? "" : ", ") + n;
    *error = "unknown ground model '" + name + "' (known: " + list + ")";
  }
  return nullptr;
}

}  // namespace ladar_perception
