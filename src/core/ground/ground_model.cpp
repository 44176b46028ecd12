// Ground models by name (ground_segment --method, the nodelets' `method` parameter).
#include "ladar_perception/ground/ground_model.h"

#include "ladar_perception/ground/analog_signal.h"
#include "ladar_perception/ground/hough_ground.h"
#include "ladar_perception/ground/plane_fit.h"
#include "ladar_perception/ground/vertical_scan.h"

namespace ladar_perception {

std::vector<std::string> groundModelNames() {
  // The default first.
  return {"vertical_scan", "vertical_scan_thesis", "vertical_scan_bins", "hough", "plane", "analog_signal"};
}

std::unique_ptr<GroundModel> makeGroundModel(const std::string& name, std::string* error) {
  if (name == "vertical_scan" || name == "default") {
    return std::make_unique<VerticalScanGround>(verticalScanDefaultParams(), "vertical_scan");
  }
  if (name == "vertical_scan_thesis" || name == "thesis") {
    return std::make_unique<VerticalScanGround>(verticalScanThesisParams(),
                                                "vertical_scan_thesis");
  }
  if (name == "vertical_scan_bins" || name == "bins") {
    return std::make_unique<VerticalScanGround>(verticalScanBinsParams(), "vertical_scan_bins");
  }
  // The Hough ground fit (3.3.4) on each azimuth column of a 3D cloud as one vertical scan.
  if (name == "hough") return makeHoughColumnsModel();
  // The thesis's ground baselines: Algorithm 1 (3.1) and the analog signal approach (3.2).
  if (name == "plane") return std::make_unique<PlaneFitGround>();
  if (name == "analog_signal") return std::make_unique<AnalogSignalGround>();
  if (error) {
    std::string list;
    for (const std::string& n : groundModelNames()) list += (list.empty() ? "" : ", ") + n;
    *error = "unknown ground model '" + name + "' (known: " + list + ")";
  }
  return nullptr;
}

}  // namespace ladar_perception
