#include "street_textures.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "texture_noise.h"

namespace vitamin_e::synth::detail {

namespace {

// A canonical image in metres: x = column direction, y = row direction.
struct Canvas {
  cv::Mat img;
  double texel;
  Canvas(double x_m, double y_m, double texel_m, float value)
      : img(texels(y_m, texel_m), texels(x_m, texel_m), CV_32FC1, cv::Scalar(value)), texel(texel_m) {}

  cv::Rect rect(double x0, double y0, double x1, double y1) const {
    const int c0 = static_cast<int>(std::floor(x0 / texel)), c1 = static_cast<int>(std::ceil(x1 / texel));
    const int r0 = static_cast<int>(std::floor(y0 / texel)), r1 = static_cast<int>(std::ceil(y1 / texel));
    return cv::Rect(c0, r0, std::max(0, c1 - c0), std::max(0, r1 - r0)) & cv::Rect(0, 0, img.cols, img.rows);
  }
  void fill(double x0, double y0, double x1, double y1, double value) {
    const cv::Rect r = rect(x0, y0, x1, y1);
    if (r.area() > 0) img(r).setTo(cv::Scalar(value));
  }
  void add(double x0, double y0, double x1, double y1, double value) {
    const cv::Rect r = rect(x0, y0, x1, y1);
    if (r.area() > 0) img(r) += cv::Scalar(value);
  }
  // Linear gradient over a rectangle (reflections on glass): value + slope * (position - centre).
  void gradient(double x0, double y0, double x1, double y1, double value, double sx, double sy) {
    const cv::Rect r = rect(x0, y0, x1, y1);
    const double cx = 0.5 * (r.x + r.x + r.width), cy = 0.5 * (r.y + r.y + r.height);
    for (int i = r.y; i < r.y + r.height; ++i) {
      float* row = img.ptr<float>(i);
      for (int j = r.x; j < r.x + r.width; ++j)
        row[j] = static_cast<float>(value + texel * (sx * (j - cx) + sy * (i - cy)));
    }
  }
  void disc(double x, double y, double radius, double value) {
    cv::circle(img, cv::Point(static_cast<int>(x / texel), static_cast<int>(y / texel)),
               std::max(1, static_cast<int>(radius / texel)), cv::Scalar(value), cv::FILLED, cv::LINE_8);
  }
  void ring(double x, double y, double radius, double width, double value) {
    cv::circle(img, cv::Point(static_cast<int>(x / texel), static_cast<int>(y / texel)),
               std::max(1, static_cast<int>(radius / texel)), cv::Scalar(value),
               std::max(1, static_cast<int>(width / texel)), cv::LINE_8);
  }
  double width() const { return img.cols * texel; }
  double height() const { return img.rows * texel; }
};

// Value-noise octaves from lambda_max down to lambda_min (or 2 texels),
// amplitude amp * (lambda / lambda_max)^exponent.
void octaves(Canvas* c, double lambda_max, double lambda_min, double amp, double exponent, Rng* rng) {
  for (double lambda = lambda_max; lambda >= lambda_min * 0.999; lambda /= 1.83) {
    const double px = lambda / c->texel;
    if (px < 2.0) break;
    addValueNoise(&c->img, px, amp * std::pow(lambda / lambda_max, exponent), rng);
  }
}

void finish(cv::Mat* img) {
  cv::GaussianBlur(*img, *img, cv::Size(3, 3), 0.5);
  cv::min(*img, 0.98, *img);
  cv::max(*img, 0.02, *img);
}

double glassValue(Rng* rng) { return rng->uniform() < 0.2 ? rng->uniform(0.45, 0.8) : rng->uniform(0.05, 0.3); }

}  // namespace

int texels(double extent_m, double texel_m) {
  return std::max(2, static_cast<int>(std::ceil(extent_m / texel_m - 1e-9)));
}

cv::Mat flatTexture(float value) { return cv::Mat(2, 2, CV_32FC1, cv::Scalar(value)); }

cv::Mat plainWallTexture(double width_m, double height_m, double texel_m, Rng* rng) {
  const double wall = rng->uniform(0.35, 0.75);
  Canvas c(width_m, height_m, texel_m, static_cast<float>(wall));
  octaves(&c, 3.0, 0.04, 0.07, 0.5, rng);
  addShapes(&c.img, texel_m, 0.1, 1.5, 0.6, 0.1, rng);
  finish(&c.img);
  return c.img;
}

cv::Mat facadeTexture(double width_m, double height_m, double texel_m, Rng* rng) {
  const double wall = rng->uniform(0.35, 0.78);
  Canvas c(width_m, height_m, texel_m, static_cast<float>(wall));
  // Plaster: low-contrast noise at every scale, stains and patches.
  octaves(&c, 2.5, 0.04, 0.06, 0.45, rng);
  addShapes(&c.img, texel_m, 0.06, 1.0, 1.2, 0.08, rng);

  // The building's style.
  const double ground_h = rng->uniform(3.6, 4.6), floor_h = rng->uniform(2.8, 3.4);
  const double bay = rng->uniform(2.2, 3.6);
  const double win_w = rng->uniform(0.9, std::min(1.6, bay - 0.7));
  const double win_h = rng->uniform(1.2, std::min(1.8, floor_h - 1.0));
  const double sill = rng->uniform(0.8, 1.0);
  const double frame_w = rng->uniform(0.05, 0.1);
  const double frame_v = std::clamp(wall + (rng->uniform() < 0.5 ? -1.0 : 1.0) * rng->uniform(0.15, 0.3), 0.05, 0.95);
  const int mullions = static_cast<int>(rng->uniform(0.0, 3.0));  // 0 none, 1 vertical, 2 cross
  const bool bands = rng->uniform() < 0.5;
  const double band_h = rng->uniform(0.15, 0.35);
  const double band_v = std::clamp(wall + rng->uniform(-0.15, 0.15), 0.05, 0.95);
  const int n_bays = std::max(1, static_cast<int>((width_m - 0.6) / bay));
  const double x_start = 0.5 * (width_m - n_bays * bay);

  // What makes one pane unlike the next: reflections and what is behind the glass.
  auto pane = [&](double x0, double y0, double x1, double y1) {
    const int n = 1 + static_cast<int>(rng->uniform(0.0, 3.0));
    for (int k = 0; k < n; ++k) {
      const double w = rng->uniform(0.1, 0.6) * (x1 - x0), h = rng->uniform(0.1, 0.8) * (y1 - y0);
      const double x = rng->uniform(x0, x1 - w), y = rng->uniform(y0, y1 - h);
      c.add(x, y, x + w, y + h, (rng->uniform() < 0.5 ? -1.0 : 1.0) * rng->uniform(0.06, 0.2));
    }
    const cv::Rect r = c.rect(x0, y0, x1, y1);
    if (r.width > 4 && r.height > 4) {
      cv::Mat roi = c.img(r);
      addValueNoise(&roi, 0.25 / texel_m, 0.06, rng);
    }
  };
  // Plinth.
  c.add(0.0, 0.0, width_m, 0.4, -0.1);
  // Upper floors: a window per bay and floor, each with its own glass, blind and reflection.
  auto window = [&](double xc, double z0, double w, double h) {
    c.fill(xc - 0.5 * w - frame_w, z0 - frame_w, xc + 0.5 * w + frame_w, z0 + h + frame_w, frame_v);
    const double g = glassValue(rng);
    c.gradient(xc - 0.5 * w, z0, xc + 0.5 * w, z0 + h, g, rng->uniform(-0.12, 0.12), rng->uniform(-0.12, 0.12));
    pane(xc - 0.5 * w, z0, xc + 0.5 * w, z0 + h);
    if (rng->uniform() < 0.35) {  // a blind or curtain from the top
      const double depth = rng->uniform(0.15, 0.7) * h;
      c.fill(xc - 0.5 * w, z0 + h - depth, xc + 0.5 * w, z0 + h, rng->uniform(0.5, 0.9));
    }
    if (mullions >= 1) c.fill(xc - 0.5 * frame_w, z0, xc + 0.5 * frame_w, z0 + h, frame_v);
    if (mullions == 2) c.fill(xc - 0.5 * w, z0 + 0.62 * h, xc + 0.5 * w, z0 + 0.62 * h + frame_w, frame_v);
    c.fill(xc - 0.5 * w - 1.5 * frame_w, z0 - frame_w - 0.06, xc + 0.5 * w + 1.5 * frame_w, z0 - frame_w,
           std::min(0.95, wall + 0.18));  // sill
  };
  for (double z = ground_h; z + floor_h <= height_m - 0.4; z += floor_h) {
    if (bands) c.fill(0.0, z - 0.5 * band_h, width_m, z + 0.5 * band_h, band_v + rng->uniform(-0.03, 0.03));
    for (int b = 0; b < n_bays; ++b) {
      if (rng->uniform() < 0.06) continue;  // bricked up / a wall
      window(x_start + (b + 0.5) * bay, z + sill, win_w, win_h);
    }
  }
  // Street level: shop fronts with signs and doors, or windows and a door.
  if (ground_h < height_m - 0.5) {
    if (rng->uniform() < 0.65) {
      for (double x = 0.3; x < width_m - 2.5;) {
        const double unit = std::min(rng->uniform(3.0, 6.5), width_m - 0.3 - x);
        if (unit < 2.5) break;
        const double glass = glassValue(rng) * 0.8;
        c.fill(x, 0.35, x + unit - 1.5, ground_h - 0.95, frame_v);
        c.gradient(x + 0.08, 0.43, x + unit - 1.58, ground_h - 1.03, glass, rng->uniform(-0.06, 0.06),
                   rng->uniform(-0.1, 0.1));
        pane(x + 0.08, 0.43, x + unit - 1.58, ground_h - 1.03);
        c.fill(x + unit - 1.35, 0.0, x + unit - 0.25, 2.25, rng->uniform(0.12, 0.5));  // door
        c.fill(x + unit - 0.45, 1.0, x + unit - 0.38, 1.15, 0.85);                     // handle
        // The sign: a band with "letters" of a contrasting intensity.
        const double sign_v = rng->uniform(0.1, 0.9);
        const double z0 = ground_h - 0.85, z1 = ground_h - 0.3;
        c.fill(x, z0, x + unit, z1, sign_v);
        const double letter_v = sign_v > 0.5 ? rng->uniform(0.05, 0.3) : rng->uniform(0.7, 0.95);
        for (double lx = x + rng->uniform(0.2, 0.6); lx < x + unit - 0.4;) {
          const double lw = rng->uniform(0.08, 0.25);
          if (rng->uniform() < 0.85) c.fill(lx, z0 + 0.12, lx + lw, z1 - 0.12, letter_v);
          lx += lw + rng->uniform(0.05, 0.15) + (rng->uniform() < 0.15 ? 0.3 : 0.0);
        }
        x += unit + rng->uniform(0.2, 0.8);
      }
    } else {
      const int door_bay = static_cast<int>(rng->uniform(0.0, n_bays));
      for (int b = 0; b < n_bays; ++b) {
        const double xc = x_start + (b + 0.5) * bay;
        if (b == door_bay) {
          c.fill(xc - 0.6, 0.0, xc + 0.6, 2.4, frame_v);
          c.fill(xc - 0.5, 0.0, xc + 0.5, 2.3, rng->uniform(0.1, 0.45));
        } else {
          window(xc, 1.1, win_w, std::min(win_h, ground_h - 1.6));
        }
      }
    }
  }
  // A drainpipe, and a cornice at the top.
  if (rng->uniform() < 0.5) {
    const double xp = x_start + static_cast<int>(rng->uniform(0.0, n_bays + 1)) * bay;
    c.fill(xp - 0.05, 0.0, xp + 0.05, height_m, std::max(0.05, wall - 0.18));
  }
  c.fill(0.0, height_m - 0.35, width_m, height_m, std::clamp(wall + rng->uniform(-0.2, 0.2), 0.05, 0.95));
  // Dirt over everything and grime near the ground.
  octaves(&c, 0.6, 0.06, 0.035, 0.3, rng);
  for (int i = 0; i < c.img.rows; ++i) {
    cv::Mat row = c.img.row(i);
    row *= 0.85 + 0.15 * std::min(1.0, (i * texel_m) / 1.5);
  }
  finish(&c.img);
  return c.img;
}

cv::Mat carSideTexture(double length_m, double height_m, double texel_m, double body, Rng* rng) {
  Canvas c(length_m, height_m, texel_m, static_cast<float>(body));
  octaves(&c, 0.8, 0.06, 0.04, 0.3, rng);
  const double glass = rng->uniform(0.06, 0.25);
  const double z_win = 0.62 * height_m;
  c.gradient(0.65, z_win, length_m - 0.55, height_m - 0.07, glass, rng->uniform(-0.1, 0.1), rng->uniform(-0.15, 0.15));
  const double b_pillar = rng->uniform(0.42, 0.5) * length_m;
  c.fill(b_pillar - 0.05, z_win, b_pillar + 0.05, height_m - 0.07, body * 0.8);
  const double seam_v = std::max(0.03, body - 0.25);
  for (const double xs : {0.28 * length_m, b_pillar, 0.72 * length_m}) c.fill(xs - 0.01, 0.3, xs + 0.01, z_win, seam_v);
  c.fill(0.1, 0.5 * height_m, length_m - 0.1, 0.5 * height_m + 0.02, std::min(0.95, body + 0.12));  // crease
  for (const double xs : {0.28 * length_m, b_pillar})
    c.fill(xs + 0.12, 0.58 * height_m - 0.05, xs + 0.28, 0.58 * height_m - 0.02, 0.7);
  c.fill(0.0, 0.0, length_m, 0.22, 0.07);  // under the body
  const double wheel_r = rng->uniform(0.29, 0.34), rim_v = rng->uniform(0.35, 0.75);
  for (const double xw : {0.82, length_m - 0.85}) {
    c.disc(xw, wheel_r, wheel_r + 0.06, std::max(0.03, body * 0.4));  // wheel arch
    c.disc(xw, wheel_r, wheel_r, 0.06);
    c.disc(xw, wheel_r, 0.6 * wheel_r, rim_v);
    c.ring(xw, wheel_r, 0.4 * wheel_r, 0.03, rim_v * 0.6);
    c.disc(xw, wheel_r, 0.1, 0.2);
  }
  finish(&c.img);
  return c.img;
}

cv::Mat carEndTexture(double width_m, double height_m, double texel_m, double body, bool front, Rng* rng) {
  Canvas c(width_m, height_m, texel_m, static_cast<float>(body));
  octaves(&c, 0.6, 0.06, 0.04, 0.3, rng);
  const double z_win = 0.62 * height_m;
  c.gradient(0.15, z_win, width_m - 0.15, height_m - 0.08, rng->uniform(0.06, 0.25), rng->uniform(-0.1, 0.1), 0.0);
  c.fill(0.0, 0.15, width_m, 0.32, body * 0.6);  // bumper
  const double light_v = front ? rng->uniform(0.7, 0.95) : rng->uniform(0.2, 0.4);
  c.fill(0.08, 0.5 * height_m - 0.08, 0.42, 0.5 * height_m + 0.05, light_v);
  c.fill(width_m - 0.42, 0.5 * height_m - 0.08, width_m - 0.08, 0.5 * height_m + 0.05, light_v);
  if (front) c.fill(0.5 * width_m - 0.35, 0.34, 0.5 * width_m + 0.35, 0.5 * height_m - 0.05, 0.1);  // grille
  // The plate: bright, with dark characters.
  const double px0 = 0.5 * width_m - 0.26, pz0 = front ? 0.2 : 0.36;
  c.fill(px0, pz0, px0 + 0.52, pz0 + 0.11, 0.9);
  for (double x = px0 + 0.04; x < px0 + 0.46;) {
    const double w = rng->uniform(0.025, 0.045);
    c.fill(x, pz0 + 0.02, x + w, pz0 + 0.09, 0.1);
    x += w + rng->uniform(0.015, 0.04);
  }
  finish(&c.img);
  return c.img;
}

cv::Mat carTopTexture(double length_m, double width_m, double texel_m, double body, Rng* rng) {
  Canvas c(length_m, width_m, texel_m, static_cast<float>(body));
  octaves(&c, 0.8, 0.06, 0.05, 0.3, rng);
  const double a = rng->uniform(0.2, 0.28) * length_m, b = rng->uniform(0.72, 0.8) * length_m;
  c.gradient(a, 0.12, a + 0.45, width_m - 0.12, rng->uniform(0.06, 0.25), 0.0, rng->uniform(-0.1, 0.1));
  c.gradient(b - 0.35, 0.12, b, width_m - 0.12, rng->uniform(0.06, 0.25), 0.0, rng->uniform(-0.1, 0.1));
  if (rng->uniform() < 0.3) c.fill(a + 0.6, 0.4, b - 0.6, width_m - 0.4, 0.1);  // sunroof
  finish(&c.img);
  return c.img;
}

cv::Mat roadTexture(double length_m, double width_m, double texel_m, bool markings, bool zebra_at_start,
                    bool zebra_at_end, Rng* rng) {
  Canvas c(length_m, width_m, texel_m, static_cast<float>(rng->uniform(0.26, 0.36)));
  // Asphalt: grain at every scale, repairs, cracks and stains.
  octaves(&c, 1.5, 0.04, 0.05, 0.3, rng);
  addShapes(&c.img, texel_m, 0.04, 0.25, 25.0, 0.06, rng);
  addShapes(&c.img, texel_m, 0.3, 2.5, 0.08, 0.06, rng);
  if (markings) {
    // Dashed centre line: 3 m dashes, 6 m gaps, worn.
    const double phase = rng->uniform(0.0, 9.0);
    for (double x = -phase; x < length_m; x += 9.0)
      c.fill(x, 0.5 * width_m - 0.06, x + 3.0, 0.5 * width_m + 0.06, 0.82);
    // Manholes in the lanes.
    for (double x = rng->uniform(3.0, 25.0); x < length_m - 1.0; x += rng->uniform(15.0, 40.0)) {
      const double y = 0.5 * width_m + (rng->uniform() < 0.5 ? -1.0 : 1.0) * rng->uniform(1.0, 2.0);
      c.disc(x, y, 0.32, 0.18);
      c.ring(x, y, 0.22, 0.04, 0.38);
      c.ring(x, y, 0.1, 0.03, 0.38);
    }
    // Zebra crossings: bars along the street, 0.5 m wide and apart.
    auto zebra = [&](double x0) {
      for (double y = 0.6; y + 0.5 < width_m - 0.5; y += 1.0) c.fill(x0, y, x0 + 3.0, y + 0.5, 0.8);
    };
    if (zebra_at_start && length_m > 10.0) zebra(1.5);
    if (zebra_at_end && length_m > 10.0) zebra(length_m - 4.5);
  }
  // Wear of everything painted.
  octaves(&c, 0.5, 0.05, 0.03, 0.2, rng);
  finish(&c.img);
  return c.img;
}

cv::Mat sidewalkTexture(double length_m, double width_m, double texel_m, Rng* rng) {
  const double base = rng->uniform(0.45, 0.7), tile = rng->uniform(0.3, 0.5);
  const bool bond = rng->uniform() < 0.5;
  Canvas c(length_m, width_m, texel_m, static_cast<float>(base));
  // Paving slabs, each of its own intensity, with dark joints.
  for (double y = 0.0; y < width_m; y += tile) {
    const double shift = bond && static_cast<int>(y / tile) % 2 ? 0.5 * tile : 0.0;
    for (double x = -shift; x < length_m; x += tile) {
      c.fill(x, y, x + tile, y + tile, base + rng->uniform(-0.07, 0.07));
      c.fill(x, y, x + texel_m, y + tile, base - 0.15);
    }
    c.fill(0.0, y, length_m, y + texel_m, base - 0.15);
  }
  octaves(&c, 1.0, 0.04, 0.04, 0.3, rng);
  addShapes(&c.img, texel_m, 0.08, 0.7, 0.4, 0.1, rng);
  finish(&c.img);
  return c.img;
}

cv::Mat kerbTexture(double length_m, double height_m, double texel_m, Rng* rng) {
  const double base = rng->uniform(0.5, 0.7);
  Canvas c(length_m, height_m, texel_m, static_cast<float>(base));
  for (double x = rng->uniform(0.0, 1.0); x < length_m; x += 1.0) {
    c.fill(x, 0.0, x + 1.0, height_m, base + rng->uniform(-0.08, 0.08));
    c.fill(x, 0.0, x + texel_m, height_m, base - 0.2);
  }
  octaves(&c, 0.5, 0.04, 0.04, 0.3, rng);
  finish(&c.img);
  return c.img;
}

}  // namespace vitamin_e::synth::detail
