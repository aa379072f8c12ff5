#include "hidden_rooms/simulation/laser_caster.h"

#include <cmath>
#include <limits>

#include <box2d/box2d.h>

namespace hidden_rooms::simulation {

namespace {

// The closest fixture along a ray, skipping one body.
class ClosestHit : public b2RayCastCallback {
 public:
  explicit ClosestHit(const b2Body* ignored) : ignored_(ignored) {}
  float ReportFixture(b2Fixture* fixture, const b2Vec2&, const b2Vec2&, float fraction) override {
    if (fixture->GetBody() == ignored_) return -1.0f;  // filter: go on as if it were not there
    fraction_ = fraction;
    return fraction;  // clip the ray here: only closer hits are reported from now on
  }
  float fraction() const { return fraction_; }

 private:
  const b2Body* ignored_;
  float fraction_ = 1.0f;
};

}  // namespace

void Box2dLaserCaster::cast(const common::Pose2& laser_pose, const common::LaserGeometry& laser,
                            std::vector<float>* ranges) const {
  ranges->resize(static_cast<size_t>(laser.beams));
  const b2Vec2 start(static_cast<float>(laser_pose.x), static_cast<float>(laser_pose.y));
  for (int k = 0; k < laser.beams; ++k) {
    const double angle = laser_pose.yaw + laser.angle_min + k * laser.angle_increment;
    const b2Vec2 end(static_cast<float>(laser_pose.x + laser.max_range * std::cos(angle)),
                     static_cast<float>(laser_pose.y + laser.max_range * std::sin(angle)));
    ClosestHit hit(ignored_);
    world_->RayCast(&hit, start, end);
    (*ranges)[k] = hit.fraction() < 1.0f ? static_cast<float>(hit.fraction() * laser.max_range)
                                         : static_cast<float>(laser.max_range);
  }
}

GridLaserCaster::GridLaserCaster(const cv::Mat1b& occupied, double resolution, const common::Point2& origin)
    : width_(occupied.cols), height_(occupied.rows), resolution_(resolution), origin_(origin) {
  cells_.resize(static_cast<size_t>(width_) * height_);
  for (int row = 0; row < height_; ++row) {
    const uchar* line = occupied.ptr<uchar>(row);
    uint8_t* target = cells_.data() + static_cast<size_t>(height_ - 1 - row) * width_;
    for (int col = 0; col < width_; ++col) target[col] = line[col] != 0 ? 1 : 0;
  }
}

double GridLaserCaster::castRay(const common::Point2& start, const common::Point2& direction, double max_range) const {
  // Grid coordinates: cell (i, j) spans [i, i + 1) x [j, j + 1), j counted from the bottom.
  const double gx = (start.x() - origin_.x()) / resolution_, gy = (start.y() - origin_.y()) / resolution_;
  const double dx = direction.x(), dy = direction.y();
  const double inf = std::numeric_limits<double>::infinity();
  // Clip the ray to the grid's box (slab method), in metres along the ray.
  double t_enter = 0.0, t_exit = max_range;
  const double box[2][2] = {{0.0, static_cast<double>(width_)}, {0.0, static_cast<double>(height_)}};
  const double g[2] = {gx, gy}, d[2] = {dx, dy};
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(d[axis]) < 1e-12) {
      if (g[axis] < box[axis][0] || g[axis] >= box[axis][1]) return max_range;
      continue;
    }
    double t0 = (box[axis][0] - g[axis]) * resolution_ / d[axis], t1 = (box[axis][1] - g[axis]) * resolution_ / d[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
  }
  if (t_enter >= t_exit) return max_range;
  const double px = gx + t_enter * dx / resolution_, py = gy + t_enter * dy / resolution_;
  int i = std::min(std::max(static_cast<int>(std::floor(px)), 0), width_ - 1);
  int j = std::min(std::max(static_cast<int>(std::floor(py)), 0), height_ - 1);
  const int step_i = dx > 0 ? 1 : -1, step_j = dy > 0 ? 1 : -1;
  // Distance along the ray (metres) to the next vertical / horizontal cell border, and between borders.
  double t_max_x = std::abs(dx) < 1e-12 ? inf : ((i + (dx > 0 ? 1 : 0)) - gx) * resolution_ / dx;
  double t_max_y = std::abs(dy) < 1e-12 ? inf : ((j + (dy > 0 ? 1 : 0)) - gy) * resolution_ / dy;
  const double t_delta_x = std::abs(dx) < 1e-12 ? inf : resolution_ / std::abs(dx);
  const double t_delta_y = std::abs(dy) < 1e-12 ? inf : resolution_ / std::abs(dy);
  double t = t_enter;
  while (true) {
    if (cells_[static_cast<size_t>(j) * width_ + i] != 0) return std::min(t, max_range);
    if (t_max_x < t_max_y) {
      t = t_max_x;
      t_max_x += t_delta_x;
      i += step_i;
      if (i < 0 || i >= width_) return max_range;
    } else {
      t = t_max_y;
      t_max_y += t_delta_y;
      j += step_j;
      if (j < 0 || j >= height_) return max_range;
    }
    if (t >= max_range) return max_range;
  }
}

void GridLaserCaster::cast(const common::Pose2& laser_pose, const common::LaserGeometry& laser,
                           std::vector<float>* ranges) const {
  ranges->resize(static_cast<size_t>(laser.beams));
  const common::Point2 start(laser_pose.x, laser_pose.y);
  for (int k = 0; k < laser.beams; ++k) {
    const double angle = laser_pose.yaw + laser.angle_min + k * laser.angle_increment;
    (*ranges)[k] =
        static_cast<float>(castRay(start, common::Point2(std::cos(angle), std::sin(angle)), laser.max_range));
  }
}

}  // namespace hidden_rooms::simulation
