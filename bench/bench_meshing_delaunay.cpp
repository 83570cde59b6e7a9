// Timing of the 2D Delaunay triangulation (meshing::delaunayTriangulate) on
// uniformly random points in a 752x480 image, the size of a frame's tracked
// points: median and p95 wall-clock and thread CPU ms over repeated runs.
//   bench_meshing_delaunay [--points N] [--repeats R] [--seed S]
// Last line of the output: JSON summary.
#include <cstdio>
#include <random>
#include <vector>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/meshing/delaunay.h"

namespace {

const char* const kUsage = "usage: bench_meshing_delaunay [--points N] [--repeats R] [--seed S]\n"
                           "  --points N    random points in a 752x480 image (default 10000)\n"
                           "  --repeats R   triangulations timed (default 30)\n"
                           "  --seed S      random seed (default 3)\n";

}  // namespace

int main(int argc, char** argv) {
  namespace cli = vitamin_e::cli;
  int points = 10000, repeats = 30;
  unsigned seed = 3;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.value("--points", &points) || args.value("--repeats", &repeats) || args.value("--seed", &seed)) continue;
    args.unknown();
  }
  if (points < 3) cli::fail("--points must be >= 3");
  if (repeats < 1) cli::fail("--repeats must be >= 1");

  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector2d> p(static_cast<std::size_t>(points));
  for (auto& q : p) q = {752.0 * u(rng), 480.0 * u(rng)};
  std::vector<double> wall, cpu;
  std::size_t triangles = 0;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = vitamin_e::TimingClock::now();
    const double c0 = vitamin_e::threadCpuMs();
    triangles = vitamin_e::meshing::delaunayTriangulate(p).size();
    cpu.push_back(vitamin_e::threadCpuMs() - c0);
    wall.push_back(vitamin_e::elapsedMs(t0));
  }
  const double wall_med = vitamin_e::percentile(wall, 50.0), wall_p95 = vitamin_e::percentile(wall, 95.0);
  const double cpu_med = vitamin_e::percentile(cpu, 50.0);
  std::printf("delaunay: %d points -> %zu triangles, %d runs: wall median %.2f ms, p95 %.2f ms; CPU median %.2f ms\n",
              points, triangles, repeats, wall_med, wall_p95, cpu_med);
  std::printf("{\"points\":%d,\"triangles\":%zu,\"repeats\":%d,\"ms_median\":%.3f,\"ms_p95\":%.3f,"
              "\"cpu_ms_median\":%.3f}\n",
              points, triangles, repeats, wall_med, wall_p95, cpu_med);
  return 0;
}
