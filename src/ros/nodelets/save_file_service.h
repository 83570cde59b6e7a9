#pragma once
// The nodelets' vitamin_e/SaveFile services (save_trajectory, save_map, export_points,
// save_mesh, save_tsdf) answer alike: the request's path, else the file parameter's.
#include <string>

#include "vitamin_e/SaveFile.h"

namespace vitamin_e_ros {

// Fills *res: refused (success false, the reason in message) when `refusal` is not empty
// or when neither the request nor the parameter ~param gives a path; else
// save(path, &res->message) decides. Returns true when a file was attempted (the caller
// logs res->message).
template <typename Save>
bool answerSaveFile(const vitamin_e::SaveFile::Request& req, const std::string& param_path, const char* param,
                    const std::string& refusal, vitamin_e::SaveFile::Response* res, Save save) {
  const std::string path = req.path.empty() ? param_path : req.path;
  if (!refusal.empty() || path.empty()) {
    res->success = false;
    res->message = !refusal.empty() ? refusal : std::string("no path given and ~") + param + " not set";
    return false;
  }
  res->success = save(path, &res->message);
  return true;
}

}  // namespace vitamin_e_ros
