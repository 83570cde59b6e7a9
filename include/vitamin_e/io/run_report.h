#pragma once
// What an offline run reports: counters and per-stage timings gathered frame by
// frame, written as stats.json; and the progress line the runner prints.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::io {

struct RunStats {
  std::string dataset;             // path as given
  std::string dataset_kind;        // "euroc", ...
  std::string config;              // config file ("" = defaults)
  std::string loaded_map;          // map file the run started in ("" = none; with one, no initialization:
                                   // first_init_frame stays -1)
  bool localization_only = false;  // the loaded map was not changed
  std::size_t stride = 1;          // every stride-th input frame was processed
  std::size_t frames = 0;          // frames given to the system
  std::size_t tracked_frames = 0;
  std::size_t skipped_frames = 0;      // unreadable images (warned and skipped)
  int init_retries = 0;                // re-initializations (new maps) after a loss
  int relocalizations = 0;             // losses recovered in the existing map
  long long first_init_frame = -1;     // frame at which the first map was built (-1: never)
  std::size_t tracked_since_init = 0;  // tracked frames from that frame on
  std::size_t reused_map_points = 0;   // map points taken over by new tracks (map reuse)
  std::size_t map_points = 0;          // points written to points.ply
  bool interrupted = false;            // stopped by SIGINT/SIGTERM
  double wall_time_s = 0.0;
  double peak_rss_mb = 0.0;
  std::vector<double> points_per_frame;         // tracked points of each frame
  std::vector<double> mapped_points_per_frame;  // of which with a 3D position
  StageTimings timing;                          // per-stage ms, with a "total" stage
  // CPU ms per processed frame of each stage on its own thread ("image_load", "tracking",
  // "mapping", "mesh", "tsdf"); helper threads (the tracker's stripes) are not in it.
  std::map<std::string, double> cpu_ms;
  std::size_t dense_fused = 0;                        // frame meshes fused into the TSDF
  std::size_t dense_dropped = 0;                      // frame meshes the TSDF's queue dropped (it lagged behind)
  std::map<int, std::size_t> dense_raster_downscale;  // fused frames per TSDF raster downscale
  // Per-frame counters by name (one value per frame that has it: pipeline::FrameDiagnostics),
  // summarized in stats.json as frame_diagnostics {name: {mean, median, min, max, sum}}.
  std::map<std::string, std::vector<double>> frame_counters;
  // Frames by their tracking state and by the reason for it (pipeline::TrackingState,
  // pipeline::StateReason, by name: "tracking", "pose_failed", ...).
  std::map<std::string, std::size_t> frames_by_state;
  std::map<std::string, std::size_t> frames_by_reason;
  void addCounter(const std::string& name, double value) { frame_counters[name].push_back(value); }

  // Records one processed frame: its point counts and stage times (total_ms is
  // the runner's wall time of process()).
  void addFrame(bool tracked, std::size_t points, std::size_t mapped,
                const std::vector<std::pair<std::string, double>>& stage_ms, double total_ms);
  double successRate() const {
    return frames ? static_cast<double>(tracked_frames) / static_cast<double>(frames) : 0.0;
  }
  // Tracked frames over all frames from the first initialization on: the share
  // of frames kept once the map exists (0 when it was never built).
  double successAfterInit() const {
    if (first_init_frame < 0 || static_cast<std::size_t>(first_init_frame) >= frames) return 0.0;
    return static_cast<double>(tracked_since_init) / static_cast<double>(frames - first_init_frame);
  }
};

// Stage names for reports (the order of timing.table(reportStages(timing))):
// the system's stages in first-seen order, then "image_load", then "total".
std::vector<std::string> reportStages(const StageTimings& timing);

// stats.json: frames, tracked_frames, success_rate, init_retries, frames_by_state, frames_by_reason,
// points_per_frame {mean, median}, timing_ms {stage: {mean, median, p95}}, peak_rss_mb, ...
std::string toJson(const RunStats& stats);
// Writes toJson(stats) to path; false (and *error) when it cannot.
bool writeRunStats(const RunStats& stats, const std::string& path, std::string* error = nullptr);

// Peak resident set size of this process in MB (getrusage ru_maxrss).
double peakRssMb();

// "[#####.....]  120/2912   4.1%  23.5 fps  ETA 1m59s  tracked 95%" (bar_width 0: no bar).
std::string formatProgress(std::size_t done, std::size_t total, double elapsed_s, double tracked_ratio, int bar_width);
// "1h02m03s", "4m05s", "7s".
std::string formatDuration(double seconds);
// JSON string literal with escapes.
std::string jsonString(const std::string& s);

}  // namespace vitamin_e::io
