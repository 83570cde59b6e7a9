#include "vitamin_e/io/run_report.h"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>

namespace vitamin_e::io {

namespace {

std::string number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// {"name": count, ...} in name order.
std::string counts(const std::map<std::string, std::size_t>& by_name) {
  std::string out = "{";
  for (const auto& [name, n] : by_name)
    out += (out.size() > 1 ? ", " : "") + jsonString(name) + ": " + std::to_string(n);
  return out + "}";
}

std::string meanMedian(const std::vector<double>& v) {
  return "{\"mean\": " + number(mean(v)) + ", \"median\": " + number(percentile(v, 50.0)) + "}";
}

}  // namespace

void RunStats::addFrame(bool tracked, std::size_t points, std::size_t mapped,
                        const std::vector<std::pair<std::string, double>>& stage_ms, double total_ms) {
  ++frames;
  if (tracked) ++tracked_frames;
  points_per_frame.push_back(static_cast<double>(points));
  mapped_points_per_frame.push_back(static_cast<double>(mapped));
  for (const auto& [stage, ms] : stage_ms) {
    if (stage != "total") timing.add(stage, ms);
  }
  timing.add("total", total_ms);
}

std::vector<std::string> reportStages(const StageTimings& timing) {
  std::vector<std::string> out;
  for (const std::string& s : timing.stages()) {
    if (s != "image_load" && s != "total") out.push_back(s);
  }
  for (const char* last : {"image_load", "total"}) {
    if (timing.summary(last).count > 0) out.emplace_back(last);
  }
  return out;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string toJson(const RunStats& s) {
  std::ostringstream os;
  os << "{\n";
  os << "  \"dataset\": " << jsonString(s.dataset) << ",\n";
  os << "  \"dataset_kind\": " << jsonString(s.dataset_kind) << ",\n";
  os << "  \"config\": " << jsonString(s.config) << ",\n";
  os << "  \"loaded_map\": " << jsonString(s.loaded_map) << ",\n";
  os << "  \"localization_only\": " << (s.localization_only ? "true" : "false") << ",\n";
  os << "  \"stride\": " << s.stride << ",\n";
  os << "  \"frames\": " << s.frames << ",\n";
  os << "  \"tracked_frames\": " << s.tracked_frames << ",\n";
  os << "  \"success_rate\": " << number(s.successRate()) << ",\n";
  os << "  \"skipped_frames\": " << s.skipped_frames << ",\n";
  os << "  \"init_retries\": " << s.init_retries << ",\n";
  os << "  \"relocalizations\": " << s.relocalizations << ",\n";
  os << "  \"first_init_frame\": " << s.first_init_frame << ",\n";
  os << "  \"tracked_since_init\": " << s.tracked_since_init << ",\n";
  os << "  \"reused_map_points\": " << s.reused_map_points << ",\n";
  os << "  \"success_after_init\": " << number(s.successAfterInit()) << ",\n";
  os << "  \"frames_by_state\": " << counts(s.frames_by_state) << ",\n";
  os << "  \"frames_by_reason\": " << counts(s.frames_by_reason) << ",\n";
  os << "  \"interrupted\": " << (s.interrupted ? "true" : "false") << ",\n";
  os << "  \"map_points\": " << s.map_points << ",\n";
  os << "  \"points_per_frame\": " << meanMedian(s.points_per_frame) << ",\n";
  os << "  \"mapped_points_per_frame\": " << meanMedian(s.mapped_points_per_frame) << ",\n";
  os << "  \"frame_diagnostics\": {";
  {
    bool first = true;
    for (const auto& [name, v] : s.frame_counters) {
      if (v.empty()) continue;
      os << (first ? "" : ",") << "\n    " << jsonString(name) << ": {\"mean\": " << number(mean(v))
         << ", \"median\": " << number(percentile(v, 50.0))
         << ", \"min\": " << number(*std::min_element(v.begin(), v.end()))
         << ", \"max\": " << number(*std::max_element(v.begin(), v.end()))
         << ", \"sum\": " << number(std::accumulate(v.begin(), v.end(), 0.0)) << "}";
      first = false;
    }
    os << (first ? "" : "\n  ") << "},\n";
  }
  os << "  \"timing_ms\": {";
  const std::vector<std::string> stages = reportStages(s.timing);
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const TimingSummary t = s.timing.summary(stages[i]);
    os << (i ? "," : "") << "\n    " << jsonString(stages[i]) << ": {\"mean\": " << number(t.mean_ms)
       << ", \"median\": " << number(t.median_ms) << ", \"p95\": " << number(t.p95_ms) << ", \"count\": " << t.count
       << "}";
  }
  os << (stages.empty() ? "" : "\n  ") << "},\n";
  os << "  \"cpu_ms\": {";
  {
    bool first = true;
    for (const auto& [stage, ms] : s.cpu_ms) {
      os << (first ? "" : ",") << "\n    " << jsonString(stage) << ": " << number(ms);
      first = false;
    }
    os << (first ? "" : "\n  ") << "},\n";
  }
  os << "  \"dense\": {\"fused\": " << s.dense_fused << ", \"dropped\": " << s.dense_dropped
     << ", \"raster_downscale\": {";
  {
    bool first = true;
    for (const auto& [downscale, frames] : s.dense_raster_downscale) {
      os << (first ? "" : ", ") << "\"" << downscale << "\": " << frames;
      first = false;
    }
  }
  os << "}},\n";
  const double fps = s.wall_time_s > 0.0 ? static_cast<double>(s.frames) / s.wall_time_s : 0.0;
  os << "  \"wall_time_s\": " << number(s.wall_time_s) << ",\n";
  os << "  \"fps\": " << number(fps) << ",\n";
  os << "  \"peak_rss_mb\": " << number(s.peak_rss_mb) << "\n";
  os << "}\n";
  return os.str();
}

bool writeRunStats(const RunStats& stats, const std::string& path, std::string* error) {
  std::ofstream out(path);
  if (out) out << toJson(stats);
  if (!out) {
    if (error) *error = "cannot write '" + path + "'";
    return false;
  }
  return true;
}

double peakRssMb() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

std::string formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "?";
  const long s = std::lround(seconds);
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof(buf), "%ldh%02ldm%02lds", s / 3600, (s / 60) % 60, s % 60);
  } else if (s >= 60) {
    std::snprintf(buf, sizeof(buf), "%ldm%02lds", s / 60, s % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "%lds", s);
  }
  return buf;
}

std::string formatProgress(std::size_t done, std::size_t total, double elapsed_s, double tracked_ratio, int bar_width) {
  const double frac = total ? std::min(1.0, static_cast<double>(done) / static_cast<double>(total)) : 1.0;
  const double fps = elapsed_s > 0.0 ? static_cast<double>(done) / elapsed_s : 0.0;
  const double eta = fps > 0.0 ? static_cast<double>(total - std::min(done, total)) / fps : NAN;
  std::string out;
  if (bar_width > 0) {
    const int filled = static_cast<int>(std::floor(frac * bar_width));
    out = "[" + std::string(filled, '#') + std::string(bar_width - filled, '.') + "] ";
  }
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%zu/%zu %5.1f%%  %.1f fps  ETA %s  tracked %.0f%%", done, total, 100.0 * frac, fps,
                done >= total ? "0s" : formatDuration(eta).c_str(), 100.0 * tracked_ratio);
  return out + buf;
}

}  // namespace vitamin_e::io
