// vitamin_e_make_sequence: renders the project's own synthetic monocular sequence
// into an EuRoC ASL folder with exact ground truth: the textured room with boxes
// (figure-eight camera path, lens distortion) or a street (a town driven along
// a named path with KITTI's camera).
//   vitamin_e_make_sequence --out DIR [--scene room|street] [--path turn|fast|drive|long]
//       [--frames N] [--rate-hz HZ] [--width W --height H] [--seed S] [--speed M_PER_S]
//       [--noise SIGMA] [--distortion euroc|none] [--supersample S] [--texel M] [--boxes N]
// Bad arguments: one "error: ..." line, exit 2.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "cli.h"
#include "vitamin_e/synth/sequence.h"

namespace {

const char* const kUsage =
    "usage: vitamin_e_make_sequence --out DIR [--scene room|street] [--path turn|fast|drive|long]\n"
    "           [--frames N] [--rate-hz HZ] [--width W --height H] [--seed S] [--speed M_PER_S]\n"
    "           [--noise SIGMA] [--distortion euroc|none] [--supersample S] [--texel M] [--boxes N]\n"
    "  --out DIR          output folder (EuRoC ASL layout + groundtruth_cam0_tum.txt + scene.json)\n"
    "  --scene S          room (default): a textured room with boxes, figure-eight path, EuRoC camera;\n"
    "                     street: a town with facades, road, parked cars and a flat sky, driven along\n"
    "                     --path with KITTI's camera (1226 x 370, fx 707.09, no distortion, 10 Hz,\n"
    "                     1.65 m above the road); run it with --config config/kitti.yaml\n"
    "  --path P           street only: turn (slow straight, 90-degree left turn at walking speed, up to\n"
    "                     3 deg/frame), fast (straight, 5 -> 15 m/s), drive (default: both, KITTI 07-like)\n"
    "                     or long (fast, with 240 m at 15 m/s)\n"
    "  --frames N         number of images (room: default 400; street: default and at most the whole path)\n"
    "  --rate-hz HZ       frame rate (default 20; street 10)\n"
    "  --width/--height   image size (default 752 x 480, street 1226 x 370; intrinsics are scaled)\n"
    "  --seed S           scene, texture and noise seed (default 0)\n"
    "  --speed V          room only: mean camera speed in m/s (default 0.4)\n"
    "  --noise SIGMA      Gaussian image noise in grey levels (default 1.0)\n"
    "  --distortion D     room only: euroc (radial-tangential of EuRoC cam0, default) or none\n"
    "  --supersample S    S x S rays per pixel, 1..4 (default 1; mip filtering is always on)\n"
    "  --texel M          finest texture resolution in metres (default 0.005, street 0.02)\n"
    "  --boxes N          room only: number of boxes in the room (default 6)\n";

using vitamin_e::cli::fail;

}  // namespace

int main(int argc, char** argv) {
  vitamin_e::cli::ArgParser args(argc, argv, kUsage);  // answers -h / --help here
  // The scene first: its defaults are the starting point of every other option.
  std::string scene = "room";
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--scene") {
      if (i + 1 >= argc) fail("--scene needs a value");
      scene = argv[++i];
      if (scene != "room" && scene != "street") fail("--scene must be room or street, got '" + scene + "'");
    }
  }
  vitamin_e::synth::SequenceConfig cfg = vitamin_e::synth::defaultSequenceConfig(scene);
  const bool street = scene == "street";
  auto room_only = [&](const std::string& key) {
    if (street) fail(key + " applies to the room scene only");
  };
  std::string out, distortion, unused_scene;
  while (args.more()) {
    if (args.value("--out", &out) || args.value("--scene", &unused_scene) || args.value("--frames", &cfg.frames) ||
        args.value("--rate-hz", &cfg.rate_hz) || args.value("--width", &cfg.width) ||
        args.value("--height", &cfg.height) || args.value("--seed", &cfg.seed) ||
        args.value("--noise", &cfg.noise_sigma) || args.value("--distortion", &distortion) ||
        args.value("--supersample", &cfg.supersample) || args.value("--texel", &cfg.texel_m)) {
      continue;
    }
    // Options of one scene only: an error for the other, not a silent no-op.
    if (args.value("--path", &cfg.path)) {
      if (!street) fail("--path applies to --scene street only");
    } else if (args.value("--speed", &cfg.speed)) {
      room_only("--speed");
    } else if (args.value("--boxes", &cfg.num_boxes)) {
      room_only("--boxes");
    } else {
      args.unknown();
    }
  }
  if (distortion == "euroc") {
    room_only("--distortion euroc");
    cfg.distortion = true;
  } else if (distortion == "none") {
    cfg.distortion = false;
  } else if (!distortion.empty()) {
    fail("--distortion must be euroc or none, got '" + distortion + "'");
  }
  if (out.empty()) fail("--out DIR is required (see --help)");
  try {
    cfg.validate();
  } catch (const std::exception& e) {
    fail(e.what());
  }
  try {
    const auto stats = vitamin_e::synth::writeSequence(out, cfg, [&](int done, int total) {
      const int step = std::max(1, total / 10);
      if (done % step == 0 || done == total) std::fprintf(stderr, "  %d/%d frames\n", done, total);
    });
    if (street) {
      std::printf("wrote %d frames (street, path %s, %dx%d, %.1f Hz, seed %llu) to %s\n", stats.frames,
                  cfg.path.c_str(), cfg.width, cfg.height, cfg.rate_hz, static_cast<unsigned long long>(cfg.seed),
                  out.c_str());
    } else {
      std::printf("wrote %d frames (%dx%d, %.1f Hz, seed %llu, %s distortion) to %s\n", stats.frames, cfg.width,
                  cfg.height, cfg.rate_hz, static_cast<unsigned long long>(cfg.seed), cfg.distortion ? "euroc" : "no",
                  out.c_str());
    }
    std::printf("scene %.2f s; per frame: render %.1f ms, png %.1f ms\n", stats.scene_build_s, stats.render_ms_mean,
                stats.write_ms_mean);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  return 0;
}
