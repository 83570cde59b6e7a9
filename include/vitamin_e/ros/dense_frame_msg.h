#pragma once
// The dense reconstruction's input (fusion::DenseFrame, made by pipeline::DenseInput
// from each SLAM result) as the vitamin_e/TrackedFrame message that TrackingNodelet
// sends to TsdfMeshingNodelet, and back: the mesher fuses what vitamin_e_run fuses.
#include <string>

#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/camera/camera.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/meshing/pinhole_image.h"

namespace vitamin_e_ros {

// Fills everything but header and segment (the caller's): pose, intrinsics and
// distortion of `camera`, ids, points, the map's scaling.
void toTrackedFrameMsg(const vitamin_e::fusion::DenseFrame& frame, const vitamin_e::camera::Camera& camera,
                       vitamin_e::TrackedFrame* msg);

// The message's DenseFrame and the pinhole image its points are meshed in. False
// (and *error saying why) for a message that cannot be fused: ids and points of
// different sizes, no image size or intrinsics, a non-finite pose or point, a
// map scaling that is not finite and positive.
bool fromTrackedFrameMsg(const vitamin_e::TrackedFrame& msg, vitamin_e::fusion::DenseFrame* frame,
                         vitamin_e::meshing::PinholeImage* image, std::string* error);

}  // namespace vitamin_e_ros
