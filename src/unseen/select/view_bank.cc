// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/view_bank.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <opencv2/imgproc.hpp>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/thread_pool.h"

namespace unseen {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The render puts the bounding sphere's centre this many radii in front of the camera
// (nearly orthographic, as most objects are seen) and its outline at this share of the
// render's half side.
constexpr double kRenderDistanceRadii = 10.0;
constexpr double kSphereShareOfHalfSide = 0.9;
// A step between neighbouring grey levels of a view's unshaded render that counts fully
// (grey in [0, 1]); smaller steps count in proportion, so flat texture says little.
constexpr float kViewFullStepGrey = 0.02f;

// Centre (pixel-centre convention) and side of the square around `box`.
Eigen::Vector2d BoxCentre(const PixelRect& box) {
  return {0.5 * (box.x0 + box.x1 - 1), 0.5 * (box.y0 + box.y1 - 1)};
}
int BoxSide(const PixelRect& box) { return std::max(box.width(), box.height()); }

// The square of `image` (one channel, float) around `box`, black outside the image,
// shrunk to side x side by area averaging.
cv::Mat CutSquare(const cv::Mat& image, const PixelRect& box, int side) {
  const int s = BoxSide(box);
  const Eigen::Vector2d c = BoxCentre(box);
  const int x0 = static_cast<int>(std::lround(c.x() - 0.5 * (s - 1)));
  const int y0 = static_cast<int>(std::lround(c.y() - 0.5 * (s - 1)));
  cv::Mat square(s, s, CV_32FC1, cv::Scalar(0));
  const cv::Rect inside = cv::Rect(x0, y0, s, s) & cv::Rect(0, 0, image.cols, image.rows);
  if (!inside.empty()) {
    image(inside).copyTo(
        square(cv::Rect(inside.x - x0, inside.y - y0, inside.width, inside.height)));
  }
  cv::Mat patch;
  cv::resize(square, patch, cv::Size(side, side), 0, 0,
             s >= side ? cv::INTER_AREA : cv::INTER_LINEAR);
  return patch;
}

cv::Mat Grey(const cv::Mat& image) {
  cv::Mat grey;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(grey, CV_32F, 1.0 / 255.0);
  } else {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  }
  return grey;
}

// Rotation taking object coordinates to those of a camera on the object's side `towards`
// (unit, object frame), looking at the object.
Eigen::Matrix3d LookingFrom(const Eigen::Vector3d& towards) {
  const Eigen::Vector3d z = -towards;
  const Eigen::Vector3d up =
      std::abs(z.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = up.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d cam_from_obj;
  cam_from_obj.row(0) = x.transpose();
  cam_from_obj.row(1) = y.transpose();
  cam_from_obj.row(2) = z.transpose();
  return cam_from_obj;
}

// The image of a camera turned by `angle` about its optical axis (Rz(angle) applied to
// camera-frame points): pixels turn by the same angle about the principal point.
cv::Mat TurnedAboutAxis(const cv::Mat& image, double angle, const Eigen::Vector2d& principal,
                        int interpolation) {
  const double c = std::cos(angle), s = std::sin(angle);
  const cv::Matx23d dst_from_src(c, -s, principal.x() - c * principal.x() + s * principal.y(), s, c,
                                 principal.y() - s * principal.x() - c * principal.y());
  cv::Mat turned;
  cv::warpAffine(image, turned, dst_from_src, image.size(), interpolation, cv::BORDER_CONSTANT,
                 cv::Scalar(0));
  return turned;
}

// The steps of `grey` (one channel, float) to each pixel's right and downward neighbour,
// divided by `full_step` and clipped to [-1, 1]; where `inside` (CV_8U, optional) is given,
// only between two pixels inside it. Zero elsewhere, and in the last column / row.
void SoftSteps(const cv::Mat& grey, float full_step, const cv::Mat& inside, cv::Mat* right,
               cv::Mat* down) {
  right->create(grey.size(), CV_32FC1);
  down->create(grey.size(), CV_32FC1);
  right->setTo(0);
  down->setTo(0);
  const auto in = [&](int y, int x) { return inside.empty() || inside.at<uint8_t>(y, x) != 0; };
  for (int y = 0; y < grey.rows; ++y) {
    for (int x = 0; x < grey.cols; ++x) {
      if (!in(y, x)) continue;
      const float here = grey.at<float>(y, x);
      if (x + 1 < grey.cols && in(y, x + 1)) {
        right->at<float>(y, x) =
            std::clamp((grey.at<float>(y, x + 1) - here) / full_step, -1.f, 1.f);
      }
      if (y + 1 < grey.rows && in(y + 1, x)) {
        down->at<float>(y, x) =
            std::clamp((grey.at<float>(y + 1, x) - here) / full_step, -1.f, 1.f);
      }
    }
  }
}

// The mean absolute step between neighbouring pixels (right and downward) of `grey`.
double MeanStep(const cv::Mat& grey) {
  const cv::Mat right = grey.colRange(1, grey.cols) - grey.colRange(0, grey.cols - 1);
  const cv::Mat down = grey.rowRange(1, grey.rows) - grey.rowRange(0, grey.rows - 1);
  return (cv::norm(right, cv::NORM_L1) + cv::norm(down, cv::NORM_L1)) /
         static_cast<double>(right.total() + down.total());
}

// A continuous float patch as a column vector.
Eigen::Map<const Eigen::VectorXf> AsVector(const cv::Mat& patch) {
  return {patch.ptr<float>(), static_cast<Eigen::Index>(patch.total())};
}

// One row of `rows`: a float patch as a row vector.
template <typename Rows>
void StoreRow(const cv::Mat& patch, int row, Rows* rows) {
  const cv::Mat continuous = patch.isContinuous() ? patch : patch.clone();
  rows->row(row) = AsVector(continuous).transpose();
}

}  // namespace

void ViewBankOptions::Check() const {
  UNSEEN_CHECK(num_directions >= 1 && num_directions <= 20000,
               "view bank: num_directions {} not in [1, 20000]", num_directions);
  UNSEEN_CHECK(num_rolls >= 1 && num_rolls <= 360, "view bank: num_rolls {} not in [1, 360]",
               num_rolls);
  UNSEEN_CHECK(patch_px >= 8 && patch_px <= 128, "view bank: patch_px {} not in [8, 128]",
               patch_px);
  UNSEEN_CHECK(render_px >= patch_px && render_px <= 1024,
               "view bank: render_px {} not in [patch_px = {}, 1024]", render_px, patch_px);
  UNSEEN_CHECK(silhouette_weight >= 0.0 && silhouette_weight <= 1.0,
               "view bank: silhouette_weight {} not in [0, 1]", silhouette_weight);
  UNSEEN_CHECK(appearance_step > 0.0 && appearance_step <= 100.0,
               "view bank: appearance_step {} not in (0, 100]", appearance_step);
  UNSEEN_CHECK(gradient_saturation > 0.0 && gradient_saturation <= 100.0,
               "view bank: gradient_saturation {} not in (0, 100]", gradient_saturation);
  UNSEEN_CHECK(threads >= 0 && threads <= 256, "view bank: threads {} not in [0, 256]", threads);
}

std::vector<Eigen::Vector3d> FibonacciSphere(int n) {
  std::vector<Eigen::Vector3d> points;
  points.reserve(std::max(n, 0));
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    points.emplace_back(r * std::cos(golden_angle * i), r * std::sin(golden_angle * i), z);
  }
  return points;
}

ViewBank::ViewBank(const Mesh& model, const ViewBankOptions& options,
                   const std::atomic<bool>* cancel)
    : options_(options) {
  options_.Check();
  model.Check();
  Eigen::Vector3f centre;
  float radius = 0.0f;
  model.BoundingSphere(&centre, &radius);
  UNSEEN_CHECK(radius > 0.0f, "view bank: the model has no extent (bounding radius {})", radius);
  sphere_centre_ = centre.cast<double>();
  render_distance_m_ = kRenderDistanceRadii * radius;
  const int n = options_.render_px;
  render_focal_px_ = kSphereShareOfHalfSide * 0.5 * n *
                     std::sqrt(render_distance_m_ * render_distance_m_ - radius * radius) / radius;
  const PinholeCamera camera = PinholeCamera::Centered(n, n, render_focal_px_);
  const Eigen::Vector2d principal(camera.cx, camera.cy);

  const int p = options_.patch_px;
  const int rolls = options_.num_rolls;
  const int max_views = options_.num_directions * rolls;
  for (ViewRows* m : {&step_right_, &step_down_, &outline_xx_, &outline_xy_, &outline_yy_}) {
    m->resize(max_views, p * p);
  }
  // View k of direction d fills row d * rolls + k; the directions render on the threads
  // (each its own buffers), and the rows of views seen edge-on are squeezed out after.
  std::vector<std::optional<View>> slots(max_views);
  std::vector<float> slot_weights(max_views, 0.0f);
  const std::vector<Eigen::Vector3d> directions = FibonacciSphere(options_.num_directions);
  ThreadPool pool(options_.threads);
  pool.ParallelFor(options_.num_directions, [&](int d) {
    if (cancel && cancel->load(std::memory_order_relaxed)) return;
    const Eigen::Matrix3d looking = LookingFrom(directions[d]);
    const Rigid3d cam_from_obj = Rigid3d::FromRotationMatrix(
        looking, Eigen::Vector3d(0, 0, render_distance_m_) - looking * sphere_centre_);
    RenderBuffers buffers;
    Render(model, camera, cam_from_obj, camera.ImageRect(), RenderOptions{}, &buffers);
    const cv::Mat grey = Grey(buffers.color);
    cv::Mat coverage;
    buffers.mask.convertTo(coverage, CV_32F, 1.0 / 255.0);
    for (int k = 0; k < rolls; ++k) {
      const double angle = 2.0 * kPi * k / rolls;
      const cv::Mat turned_mask = TurnedAboutAxis(coverage, angle, principal, cv::INTER_LINEAR);
      cv::Mat on;
      cv::compare(turned_mask, 0.5, on, cv::CMP_GT);
      const cv::Rect bounds = cv::boundingRect(on);
      if (bounds.width < 2 || bounds.height < 2) continue;  // seen edge-on
      const PixelRect box{bounds.x, bounds.y, bounds.x + bounds.width, bounds.y + bounds.height};
      const cv::Mat turned_grey = TurnedAboutAxis(grey, angle, principal, cv::INTER_LINEAR);
      const cv::Mat mask_patch = CutSquare(turned_mask, box, p);
      cv::Mat grey_patch = CutSquare(turned_grey, box, p);

      const int row = d * rolls + k;
      View view;
      view.cam_from_obj_rotation = Eigen::Quaterniond(
          Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * Eigen::Quaterniond(looking));
      view.centre_offset_px = BoxCentre(box) - principal;
      view.side_px = BoxSide(box);
      slots[row] = view;

      // Appearance: the steps inside the silhouette, summing to 1 in absolute value. A
      // uniform view (no texture) carries no appearance: all zero, score 0.
      cv::Mat inside;
      cv::compare(mask_patch, 0.5, inside, cv::CMP_GT);
      cv::Mat right, down;
      SoftSteps(grey_patch, kViewFullStepGrey, inside, &right, &down);
      const double total = cv::norm(right, cv::NORM_L1) + cv::norm(down, cv::NORM_L1);
      const double scale = total >= 1.0 ? 1.0 / total : 0.0;
      StoreRow(right * scale, row, &step_right_);
      StoreRow(down * scale, row, &step_down_);

      // Outline: the gradient of the silhouette, |g| n n^T = g g^T / |g|.
      cv::Mat gx, gy;
      cv::Sobel(mask_patch, gx, CV_32F, 1, 0, 3, 0.25, 0, cv::BORDER_CONSTANT);
      cv::Sobel(mask_patch, gy, CV_32F, 0, 1, 3, 0.25, 0, cv::BORDER_CONSTANT);
      cv::Mat magnitude;
      cv::magnitude(gx, gy, magnitude);
      const cv::Mat inverse = 1.0 / cv::max(magnitude, 1e-6f);
      StoreRow(gx.mul(gx).mul(inverse), row, &outline_xx_);
      StoreRow(2.0 * gx.mul(gy).mul(inverse), row, &outline_xy_);
      StoreRow(gy.mul(gy).mul(inverse), row, &outline_yy_);
      slot_weights[row] = static_cast<float>(cv::sum(magnitude)[0]);
    }
  });
  UNSEEN_CHECK(!(cancel && cancel->load()), "view bank: cancelled");
  views_.reserve(max_views);
  for (int row = 0; row < max_views; ++row) {
    if (!slots[row]) continue;
    const int kept = size();
    if (kept != row) {
      for (ViewRows* m : {&step_right_, &step_down_, &outline_xx_, &outline_xy_, &outline_yy_}) {
        m->row(kept) = m->row(row);
      }
    }
    views_.push_back(*slots[row]);
    outline_weight_.push_back(slot_weights[row]);
  }
  UNSEEN_CHECK(!views_.empty(), "view bank: the model covers no pixel from any direction");
  for (ViewRows* m : {&step_right_, &step_down_, &outline_xx_, &outline_xy_, &outline_yy_}) {
    m->conservativeResize(size(), Eigen::NoChange);
  }
}

std::vector<ViewMatch> ViewBank::Match(const cv::Mat& image, const PixelRect& box, int max_matches,
                                       double min_separation_deg) const {
  UNSEEN_CHECK(image.type() == CV_32FC3 || image.type() == CV_8UC3,
               "view bank: the image must be CV_32FC3 or CV_8UC3 (type {})", image.type());
  UNSEEN_CHECK(!box.empty(), "view bank: the object's box [{}, {}) x [{}, {}) is empty", box.x0,
               box.x1, box.y0, box.y1);
  const int p = options_.patch_px;
  const cv::Mat x = CutSquare(Grey(image), box, p);
  cv::Mat right, down;
  SoftSteps(x, static_cast<float>(options_.appearance_step * MeanStep(x)) + 1e-6f, cv::Mat(),
            &right, &down);
  cv::Mat gx, gy, magnitude;
  cv::Sobel(x, gx, CV_32F, 1, 0, 3, 0.25, 0, cv::BORDER_REPLICATE);
  cv::Sobel(x, gy, CV_32F, 0, 1, 3, 0.25, 0, cv::BORDER_REPLICATE);
  cv::magnitude(gx, gy, magnitude);
  const double saturation = options_.gradient_saturation * cv::mean(magnitude)[0] + 1e-9;
  const cv::Mat damping = 1.0 / (magnitude / saturation + 1.0);
  gx = gx.mul(damping);
  gy = gy.mul(damping);
  const double energy_per_px = (cv::sum(gx.mul(gx))[0] + cv::sum(gy.mul(gy))[0]) / (p * p);

  // Every view at once: one matrix-vector product per term.
  const cv::Mat inputs[5] = {right, down, gx.mul(gx), gx.mul(gy), gy.mul(gy)};
  const ViewRows* rows[5] = {&step_right_, &step_down_, &outline_xx_, &outline_xy_, &outline_yy_};
  Eigen::VectorXf dots[5];
  for (int t = 0; t < 5; ++t) dots[t].noalias() = *rows[t] * AsVector(inputs[t]);

  const double w = options_.silhouette_weight;
  std::vector<ViewMatch> all(size());
  for (int v = 0; v < size(); ++v) {
    ViewMatch& m = all[v];
    m.view = v;
    m.cam_from_obj_rotation = views_[v].cam_from_obj_rotation;
    m.appearance = dots[0](v) + dots[1](v);
    const double across = dots[2](v) + dots[3](v) + dots[4](v);
    const double expected = outline_weight_[v] * energy_per_px;
    const double ratio = expected > 1e-12 ? across / expected : 0.0;
    // An isotropic gradient field gives (g . n)^2 = |g|^2 / 2 on average: ratio 0.5.
    m.silhouette = (ratio - 0.5) / (ratio + 0.5);
    m.score = (1.0 - w) * m.appearance + w * m.silhouette;
  }
  std::vector<int> order(size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return all[a].score > all[b].score; });
  std::vector<ViewMatch> best;
  const double min_separation = min_separation_deg * kPi / 180.0;
  for (const int v : order) {
    if (static_cast<int>(best.size()) >= max_matches) break;
    const bool distinct = std::all_of(best.begin(), best.end(), [&](const ViewMatch& b) {
      return AngleBetween(b.cam_from_obj_rotation, all[v].cam_from_obj_rotation) >= min_separation;
    });
    if (distinct) best.push_back(all[v]);
  }
  return best;
}

Rigid3d ViewBank::CamFromObj(const ViewMatch& match, const PinholeCamera& intrinsics,
                             const PixelRect& box) const {
  UNSEEN_CHECK(match.view >= 0 && match.view < size(), "view bank: view {} not in [0, {})",
               match.view, size());
  UNSEEN_CHECK(!box.empty(), "view bank: the object's box is empty");
  const View& view = views_[match.view];
  const double scale = BoxSide(box) / view.side_px;  // image pixels per render pixel
  const double focal = std::sqrt(intrinsics.fx * intrinsics.fy);
  const double depth = render_distance_m_ * (focal / render_focal_px_) / scale;
  const Eigen::Vector2d centre_px = BoxCentre(box) - scale * view.centre_offset_px;
  const Eigen::Vector3d centre_in_cam = intrinsics.Unproject(centre_px, depth);
  const Eigen::Quaterniond onto_ray =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), centre_in_cam);
  const Eigen::Quaterniond rotation = onto_ray * view.cam_from_obj_rotation;
  return Rigid3d(rotation, centre_in_cam - rotation * sphere_centre_);
}

}  // namespace unseen
