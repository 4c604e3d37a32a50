// A Detection as JSON: everything the detector found, plus a "detections"
// list and "time_s" in the format of /work/shared/tools/score.py, so a folder
// of <scene_id>.json files can be scored as it is.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

// Layout (metres, camera frame; poses are 4x4 row-major nested arrays):
//   {"box_dims": [l, b, h],
//    "boxes": [{"camera_T_box", "score", "grasp_face": "+z", "grasp_centre",
//               "grasp_normal", "num_corners", "segments": [...]}],
//    "edges": [{"end1", "end2", "num_points", "length"}],
//    "corners": [{"position", "segments": [a, b]}],
//    "num_edge_points": N,
//    "timings_ms": {"preprocess", "edge_points", "edge_segments", "clubbing",
//                   "poses", "total"},
//    "detections": [{"pose", "score"}],   // scorer format, best first
//    "time_s": total seconds}
// Non-finite numbers come out as null.
nlohmann::json DetectionToJson(const Detection& detection, const BoxDims& dims);

// Writes DetectionToJson to path (indented).
absl::Status WriteDetectionJson(const std::string& path, const Detection& detection,
                                const BoxDims& dims);

}  // namespace cornerpose
