// Shared by the OpenNI2 tests: the bundled frames they compare against, the
// virtual camera's URI, and an .oni recorded from it with oni_record.
#pragma once

#include <string>
#include <vector>

#include "common/perception/types.h"

namespace cornerpose::openni2_test {

// data/frames/carton_s in the source tree.
std::string CartonFrames();

// "cornerpose://virtual?dir=DIR&fps=FPS".
std::string VirtualCameraUri(const std::string& directory, double fps);

// The PNGs of `directory`, in name order, back-projected with its
// intrinsics.txt the project's way (DepthToCloud); the intrinsics in *camera.
std::vector<PointCloud> ExpectedClouds(const std::string& directory, CameraIntrinsics* camera);

// The index in `expected` of the cloud `cloud` equals within `tolerance`
// metres per coordinate (NaN where and only where it is NaN), or -1.
int MatchCloud(const PointCloud& cloud, const std::vector<PointCloud>& expected,
               float tolerance = 0.001f);

// Records about `frames` frames of the virtual camera replaying `directory`
// to `out` with oni_record (at most 60 s). Empty on success, else why not.
std::string RecordOni(const std::string& directory, const std::string& out, int frames);

// The number of depth frames OpenNI2 finds in the recording `path`, or -1.
// OpenNI2's recorder runs asynchronously, so this can exceed the count asked
// of RecordOni when the machine is busy.
int OniDepthFrameCount(const std::string& path);

}  // namespace cornerpose::openni2_test
