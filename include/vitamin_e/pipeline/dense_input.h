#pragma once
// The dense reconstruction's input from the SLAM's results, frame by frame:
// the frame's triangulated points in its camera (framePointsInCamera) and the
// map's scaling so far, composed from each result's ground-scale correction
// (FrameDiagnostics::scale_correction: the map scaled about that frame's camera
// centre before its points were read). The offline runner feeds the DenseFrame
// to fusion::DenseMapper directly; the ROS tracking nodelet sends it to the
// meshing nodelet as a vitamin_e/TrackedFrame, which gives it to its
// DenseMapper: one path, one scale.
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/pipeline/frame_result.h"

namespace vitamin_e::pipeline {

class DenseInput {
 public:
  // Every result of the SLAM, in order: a result without a pose still carries
  // the scaling. The points are left empty when with_points is false (nobody
  // will fuse this frame).
  fusion::DenseFrame next(const FrameResult& result, bool with_points = true);
  // A new map (a new SLAM run, not a re-initialization inside one): its own scale.
  void reset() { map_scaling_ = fusion::MapScaling{}; }
  const fusion::MapScaling& mapScaling() const { return map_scaling_; }

 private:
  fusion::MapScaling map_scaling_;
};

}  // namespace vitamin_e::pipeline
