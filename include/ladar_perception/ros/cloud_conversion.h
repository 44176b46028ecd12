// The boundary between sensor_msgs/PointCloud2 and the core's PointCloudView, and the builder
// of fresh output clouds. No algorithm here.
#pragma once

#include <string>
#include <vector>

#include <sensor_msgs/PointCloud2.h>

#include "ladar_perception/cloud/point_cloud_view.h"
#include "ladar_perception/ground/ground_classification.h"

namespace ladar_perception {

// Describes a message's layout for the core (copies only the small field table).
CloudLayout layoutOf(const sensor_msgs::PointCloud2& msg);

// Validates the message and makes a view over its data (no copy of the points). *layout must
// outlive the view. False with a one-sentence reason on an unreadable cloud.
bool viewOf(const sensor_msgs::PointCloud2& msg, CloudLayout* layout, PointCloudView* view,
            std::string* error, CloudError* code = nullptr);

// Fresh output clouds built from the input and the per-point labels, stamped and framed like
// the input (interfaces.md):
//  - subset(): the input's fields for the points whose label equals `label`, dense (width = N).
//  - classified(): every input point with the input's fields plus float32 p_obstacle and uint8
//    label; the input's width and height are kept so organised clouds stay organised.
sensor_msgs::PointCloud2Ptr subsetCloud(const sensor_msgs::PointCloud2& in,
                                        const PointCloudView& view,
                                        const GroundClassification& result, Label label);
sensor_msgs::PointCloud2Ptr classifiedCloud(const sensor_msgs::PointCloud2& in,
                                            const PointCloudView& view,
                                            const GroundClassification& result);

// The message form of a PackedCloud (simulator and tools).
sensor_msgs::PointCloud2Ptr toMessage(const PackedCloud& cloud);

// Writes layout's fields, width, height, point_step, row_step and byte order into out (not its
// data).
void applyLayout(const CloudLayout& layout, sensor_msgs::PointCloud2* out);

}  // namespace ladar_perception
