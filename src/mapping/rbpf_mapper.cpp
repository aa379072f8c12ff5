#include "hidden_rooms/mapping/rbpf_mapper.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <optional>
#include <sstream>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/core/format.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3DPDFParticles.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/slam/CMetricMapBuilderRBPF.h>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/mapping/scan_matched_odometry.h"

namespace hidden_rooms::mapping {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Scans the rendering's checkpoint stays behind the newest (paths of the best particle part within the last ones).
constexpr size_t kCheckpointLag = 50;

mrpt::poses::CPose2D toMrpt(const common::Pose2& pose) { return mrpt::poses::CPose2D(pose.x, pose.y, pose.yaw); }
common::Pose2 fromMrpt(const mrpt::math::TPose3D& pose) { return {pose.x, pose.y, pose.yaw}; }

// The double a float was written from (0.05f -> 0.05): MRPT keeps the grid's geometry in floats.
double shortest(float value) { return std::stod(mrpt::format("%.7g", static_cast<double>(value))); }

bool finite(const common::Pose2& pose) {
  return std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.yaw);
}

// The line of an MRPT exception that says what went wrong (its text carries a banner and a stack trace).
std::string mrptMessage(const std::exception& error) {
  std::istringstream text(error.what());
  std::string line, first;
  while (std::getline(text, line)) {
    if (line.rfind("Message:", 0) == 0) return line.substr(line.find_first_not_of(' ', 8));
    if (first.empty() && !line.empty() && line.find("====") == std::string::npos) first = line;
  }
  return first;
}

// The odometry motion model from an ini section (MRPT has no loader for it); keys it lacks keep `model`'s values.
mrpt::obs::CActionRobotMovement2D::TMotionModelOptions readMotionModel(
    const mrpt::config::CConfigFileBase& ini, const std::string& file, const std::string& section = "MotionModel",
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions model = {}) {
  model.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
  auto& g = model.gaussianModel;
  g.a1 = ini.read_double(section, "a1", g.a1);
  g.a2 = ini.read_double(section, "a2", g.a2);
  g.a3 = ini.read_double(section, "a3", g.a3);
  g.a4 = ini.read_double(section, "a4", g.a4);
  g.minStdXY = ini.read_double(section, "minStdXY", g.minStdXY);
  g.minStdPHI = ini.read_double(section, "minStdPHI_deg", g.minStdPHI * 180.0 / kPi) * kPi / 180.0;
  for (double value : {g.a1, g.a2, g.a3, g.a4, g.minStdXY, g.minStdPHI})
    if (!std::isfinite(value) || value < 0.0)
      throw common::InputError(file, "[" + section + "] motion model values must be zero or positive");
  return model;
}

// Insertion options of the published grid ([PublishedMap], see config/rbpf.ini): those of the filter's grid with
// its own update certainties.
mrpt::maps::COccupancyGridMap2D::TInsertionOptions readPublishedInsertion(
    const mrpt::config::CConfigFileBase& ini, const std::string& file,
    mrpt::maps::COccupancyGridMap2D::TInsertionOptions insertion) {
  const std::string section = "PublishedMap";
  insertion.maxOccupancyUpdateCertainty =
      ini.read_float(section, "maxOccupancyUpdateCertainty", insertion.maxOccupancyUpdateCertainty);
  insertion.maxFreenessUpdateCertainty =
      ini.read_float(section, "maxFreenessUpdateCertainty", insertion.maxFreenessUpdateCertainty);
  const auto certain = [](float value) { return value > 0.5f && value < 1.0f; };
  if (!certain(insertion.maxOccupancyUpdateCertainty) ||
      !(insertion.maxFreenessUpdateCertainty == 0.0f || certain(insertion.maxFreenessUpdateCertainty)))
    throw common::InputError(
        file, "[PublishedMap] certainties must be in (0.5, 1) (maxFreenessUpdateCertainty 0: as occupancy)");
  return insertion;
}

}  // namespace

const common::OptionTable<RbpfMapperOptions>& rbpfMapperOptionTable() {
  using O = RbpfMapperOptions;
  static const common::OptionTable<O> table{
      {"config_file", &O::config_file, "MRPT ini (filter, grids, [PublishedMap], [MotionModel]); required"},
      {"config_section", &O::section, "section of the ini with the filter's options"},
  };
  return table;
}

struct RbpfMapper::Impl {
  std::unique_ptr<mrpt::slam::CMetricMapBuilderRBPF> builder;
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion_model;
  bool started = false;
  // The odometry the filter is fed: the robot's, or corrected by the scan-matching front-end ([ScanMatching]).
  std::optional<ScanMatchedOdometry> front_end;
  common::Pose2 last_odometry;      // the filter's odometry at the last scan
  common::Pose2 last_raw_odometry;  // the robot's odometry at the last scan (map -> odom is relative to it)
  std::string config_file;
  int added = 0;
  int inserted = 0;
  // With the front-end's loop closure: each entry of the particles' paths with the front-end pose it was fed,
  // anchored to the front-end's keyframe, so that the paths follow when an optimization moves the keyframes.
  struct PathAnchor {
    size_t path_index;
    KeyframeAnchor anchor;
    common::Pose2 fed;
  };
  std::vector<PathAnchor> path_anchors;
  KeyframeAnchor last_odometry_anchor;
  // The pose after every scan, anchored to the front-end's newest keyframe then (with loop closure).
  std::vector<KeyframeAnchor> scan_poses;
  int loop_closures_applied = 0;
  void followOptimizedKeyframes();

  // The published map: every inserted scan drawn again along the path of the particle whose grid MRPT calls the
  // most likely one, with the [PublishedMap] certainties (as gmapping renders its map from the best particle's
  // trajectory). Scans and their index in the particles' paths, in insertion order.
  mrpt::maps::COccupancyGridMap2D::TInsertionOptions published_insertion;
  std::vector<mrpt::obs::CObservation2DRangeScan::Ptr> inserted_scans;
  std::vector<size_t> inserted_path_index;
  // Cache of the last rendering: the grid and the poses it drew the first scans at (a new best particle whose
  // path starts with the same poses only adds the new scans).
  mutable std::optional<mrpt::maps::COccupancyGridMap2D> rendered;
  mutable std::vector<mrpt::math::TPose3D> rendered_poses;
  // A copy of the rendering after its first checkpoint_scans scans, made kCheckpointLag scans behind the newest
  // while drawing: a new path that parts from the rendered one only after them is drawn on from the copy instead of
  // from scratch (the same cells: scans are drawn in the same order at the same poses).
  mutable std::optional<mrpt::maps::COccupancyGridMap2D> checkpoint;
  mutable size_t checkpoint_scans = 0;

  size_t mappedParticle() const;
  const mrpt::maps::COccupancyGridMap2D& publishedGrid() const;
};

RbpfMapper::RbpfMapper(const RbpfMapperOptions& options) : impl_(std::make_unique<Impl>()) {
  const std::string& file = options.config_file;
  if (file.empty()) throw common::InputError("rbpf config", "no ini file given");
  if (!common::isFile(file) || !std::ifstream(file).good())
    throw common::InputError(file, "cannot read the file");
  mrpt::slam::CMetricMapBuilderRBPF::TConstructionOptions construction;
  try {
    mrpt::config::CConfigFile ini(file);
    if (!ini.sectionExists(options.section)) throw common::InputError(file, "no section [" + options.section + "]");
    construction.loadFromConfigFile(ini, options.section);
    impl_->motion_model = readMotionModel(ini, file);
    const ScanMatchingOptions scan_matching = readScanMatchingOptions(ini, file);
    if (scan_matching.enabled) {
      // The prediction's noise: [ScanMatching]'s own a1 .. minStdPHI_deg, else the filter's [MotionModel]. MRPT's
      // a2 is in metres per degree, a3 in degrees per metre.
      const auto g = readMotionModel(ini, file, "ScanMatching", impl_->motion_model).gaussianModel;
      impl_->front_end.emplace(scan_matching, ScanMatchedOdometry::MotionNoise{g.a1, g.a2 * 180.0 / kPi,
                                                                               g.a3 * kPi / 180.0, g.a4, g.minStdXY,
                                                                               g.minStdPHI});
    }
    for (const auto& initializer : construction.mapsInitializers)
      if (const auto* grid = dynamic_cast<const mrpt::maps::COccupancyGridMap2D::TMapDefinition*>(initializer.get())) {
        impl_->published_insertion = readPublishedInsertion(ini, file, grid->insertionOpts);
        break;
      }
  } catch (const common::InputError&) {
    throw;
  } catch (const std::exception& error) {
    throw common::InputError(file, "bad MRPT RBPF options: " + mrptMessage(error));
  }
  if (construction.PF_options.sampleSize == 0) throw common::InputError(file, "sampleSize must be positive");
  if (!(construction.insertionLinDistance >= 0.0f) || !(construction.localizeLinDistance >= 0.0f))
    throw common::InputError(file, "insertion and localize distances must be zero or positive");
  mrpt::random::getRandomGenerator().randomize(options.seed);
  try {
    impl_->builder = std::make_unique<mrpt::slam::CMetricMapBuilderRBPF>(construction);
  } catch (const std::exception& error) {
    throw common::InputError(file, "MRPT cannot build the filter: " + mrptMessage(error));
  }
  impl_->config_file = file;
  const mrpt::maps::CMultiMetricMap* maps = impl_->builder->getCurrentlyBuiltMetricMap();
  if (maps == nullptr || maps->countMapsByClass<mrpt::maps::COccupancyGridMap2D>() == 0)
    throw common::InputError(file, "the maps must include an occupancy grid (occupancyGrid_count = 1)");
}

RbpfMapper::~RbpfMapper() = default;

bool RbpfMapper::addScan(const common::Pose2& odometry, const common::RangeScan& scan) {
  if (scan.ranges.empty()) throw common::InputError("scan", "has no beams");
  if (!finite(scan.sensor_pose) || !std::isfinite(scan.angle_min) || !std::isfinite(scan.angle_increment) ||
      scan.angle_increment == 0.0 || !(scan.range_max > 0.0))
    throw common::InputError("scan", "non-finite pose or bad beam geometry");
  // Scan as MRPT wants it: beams from -aperture/2 to +aperture/2 counter-clockwise, the sensor yawed to the
  // middle of the scan (as toMrptScan does for ROS messages).
  const size_t n = scan.ranges.size();
  const bool reversed = scan.angle_increment < 0.0;
  const double aperture = std::abs(scan.angle_increment) * static_cast<double>(n - 1);
  const double first = reversed ? scan.angle_min + scan.angle_increment * static_cast<double>(n - 1) : scan.angle_min;
  mrpt::obs::CObservation2DRangeScan observation;
  observation.aperture = static_cast<float>(n > 1 ? aperture : 0.0);
  observation.rightToLeft = true;
  observation.maxRange = static_cast<float>(scan.range_max);
  observation.sensorPose = mrpt::poses::CPose3D(mrpt::poses::CPose2D(
      scan.sensor_pose.x, scan.sensor_pose.y, scan.sensor_pose.yaw + first + 0.5 * aperture));
  observation.resizeScan(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = reversed ? n - 1 - i : i;
    const bool valid = std::isfinite(scan.ranges[k]) && scan.valid(k);
    observation.setScanRange(i, valid ? scan.ranges[k] : static_cast<float>(scan.range_max));
    observation.setScanRangeValidity(i, valid);
  }
  return addScan(odometry, observation);
}

bool RbpfMapper::addScan(const common::Pose2& odometry, const mrpt::obs::CObservation2DRangeScan& scan) {
  if (scan.getScanSize() == 0) throw common::InputError("scan", "has no beams");
  if (!finite(odometry)) throw common::InputError("scan", "non-finite odometry pose");
  Impl& impl = *impl_;
  impl.last_raw_odometry = odometry;
  const common::Pose2 filter_odometry = impl.front_end ? impl.front_end->correct(odometry, scan) : odometry;
  if (impl.front_end && impl.front_end->loopClosures() != impl.loop_closures_applied) impl.followOptimizedKeyframes();
  if (!impl.started) {
    mrpt::poses::CPosePDFGaussian start(toMrpt(filter_odometry));
    impl.builder->initialize(mrpt::maps::CSimpleMap(), &start);
    impl.last_odometry = filter_odometry;
    impl.started = true;
  }
  auto observation = std::make_shared<mrpt::obs::CObservation2DRangeScan>(scan);
  mrpt::obs::CSensoryFrame frame;
  frame.insert(observation);

  // Odometry increment since the last scan, in the robot frame.
  mrpt::obs::CActionRobotMovement2D movement;
  movement.computeFromOdometry(toMrpt(filter_odometry) - toMrpt(impl.last_odometry), impl.motion_model);
  mrpt::obs::CActionCollection actions;
  actions.insert(movement);
  impl.last_odometry = filter_odometry;

  const size_t path_length = impl.builder->mapPDF.m_particles.front().d->robotPath.size();
  try {
    impl.builder->processActionObservation(actions, frame);
  } catch (const std::exception& error) {  // options that do not fit together (an ICP method for another map type)
    throw common::InputError(impl.config_file, "MRPT rejects these options while mapping: " + mrptMessage(error));
  }
  if (impl.front_end) {
    impl.last_odometry_anchor = impl.front_end->anchor(filter_odometry);
    const size_t length = impl.builder->mapPDF.m_particles.front().d->robotPath.size();
    for (size_t index = path_length; index < length; ++index)
      impl.path_anchors.push_back({index, impl.last_odometry_anchor, filter_odometry});
  }
  ++impl.added;
  const common::Pose2 now = pose();
  impl.scan_poses.push_back(impl.front_end ? impl.front_end->anchor(now) : KeyframeAnchor{KeyframeAnchor::kNone, now});
  const bool was_inserted = impl.builder->m_statsLastIteration.observationsInserted;
  impl.inserted += was_inserted;
  if (was_inserted) {
    impl.inserted_scans.push_back(observation);
    impl.inserted_path_index.push_back(impl.builder->mapPDF.m_particles.front().d->robotPath.size() - 1);
  }
  return was_inserted;
}

// The front-end's optimization moved its keyframes: every path entry moves as its keyframe did (the particles'
// own offsets from the front-end's poses kept), and so does the odometry the next increment is taken from.
void RbpfMapper::Impl::followOptimizedKeyframes() {
  for (PathAnchor& entry : path_anchors) {
    const common::Pose2 now = front_end->resolve(entry.anchor);
    const common::Pose2 moved = common::composePoses(now, common::invertPose(entry.fed));
    entry.fed = now;
    for (auto& particle : builder->mapPDF.m_particles) {
      mrpt::math::TPose3D& pose = particle.d->robotPath[entry.path_index];
      const common::Pose2 corrected = common::composePoses(moved, fromMrpt(pose));
      pose.x = corrected.x;
      pose.y = corrected.y;
      pose.yaw = corrected.yaw;
    }
  }
  last_odometry = front_end->resolve(last_odometry_anchor);
  loop_closures_applied = front_end->loopClosures();
}

std::vector<common::Pose2> RbpfMapper::trajectory() const {
  std::vector<common::Pose2> poses;
  poses.reserve(impl_->scan_poses.size());
  for (const KeyframeAnchor& anchor : impl_->scan_poses)
    poses.push_back(impl_->front_end ? impl_->front_end->resolve(anchor) : anchor.offset);
  return poses;
}

int RbpfMapper::scansAdded() const { return impl_->added; }
int RbpfMapper::scansInserted() const { return impl_->inserted; }

std::vector<RbpfParticle> RbpfMapper::particles() const {
  std::vector<RbpfParticle> result;
  if (!impl_->started) return result;
  const auto estimate = impl_->builder->getCurrentPoseEstimation();
  const auto* particles = dynamic_cast<const mrpt::poses::CPose3DPDFParticles*>(estimate.get());
  if (particles == nullptr || particles->m_particles.empty()) return result;
  double max_log = -std::numeric_limits<double>::infinity();
  for (const auto& p : particles->m_particles) max_log = std::max(max_log, p.log_w);
  double sum = 0.0;
  for (const auto& p : particles->m_particles) {
    result.push_back({fromMrpt(p.d), std::exp(p.log_w - max_log)});
    sum += result.back().weight;
  }
  for (RbpfParticle& p : result) p.weight /= sum;
  return result;
}

// The particle whose map getCurrentlyBuiltMetricMap() returns (MRPT picks the largest weight), so that the pose
// and the map published with it come from the same particle.
size_t RbpfMapper::Impl::mappedParticle() const {
  const mrpt::maps::CMultiMetricMap* mapped = builder->getCurrentlyBuiltMetricMap();
  const auto& all = builder->mapPDF.m_particles;
  for (size_t i = 0; i < all.size(); ++i)
    if (&all[i].d->mapTillNow == mapped) return i;
  return 0;
}

common::Pose2 RbpfMapper::pose() const {
  if (!impl_->started) return impl_->last_odometry;
  const std::vector<RbpfParticle> all = particles();
  if (all.empty()) return impl_->last_odometry;
  const size_t mapped = impl_->mappedParticle();
  return all[mapped < all.size() ? mapped : 0].pose;
}

common::Pose2 RbpfMapper::mapToOdom() const {
  return common::composePoses(pose(), common::invertPose(impl_->last_raw_odometry));
}

const mrpt::maps::COccupancyGridMap2D& RbpfMapper::Impl::publishedGrid() const {
  const auto& path = builder->mapPDF.m_particles[mappedParticle()].d->robotPath;
  size_t same = 0;  // leading scans already drawn at the same poses
  while (same < rendered_poses.size() && same < inserted_scans.size() &&
         path[inserted_path_index[same]] == rendered_poses[same])
    ++same;
  if (rendered && same < rendered_poses.size() && checkpoint && same >= checkpoint_scans) {
    rendered = *checkpoint;  // another path, the same as far as the checkpoint: draw on from there
    rendered_poses.resize(checkpoint_scans);
  } else if (!rendered || same < rendered_poses.size()) {  // another path: draw all scans again
    const auto filter_grid = builder->getCurrentlyBuiltMetricMap()->mapByClass<mrpt::maps::COccupancyGridMap2D>(0);
    rendered.emplace(filter_grid->getXMin(), filter_grid->getXMax(), filter_grid->getYMin(), filter_grid->getYMax(),
                     filter_grid->getResolution());
    rendered->insertionOptions = published_insertion;
    rendered_poses.clear();
    checkpoint.reset();
    checkpoint_scans = 0;
  }
  const size_t next_checkpoint = inserted_scans.size() > kCheckpointLag ? inserted_scans.size() - kCheckpointLag : 0;
  for (size_t k = rendered_poses.size(); k < inserted_scans.size(); ++k) {
    if (k == next_checkpoint && k >= checkpoint_scans + kCheckpointLag) {
      checkpoint = *rendered;
      checkpoint_scans = k;
    }
    const mrpt::math::TPose3D& pose = path[inserted_path_index[k]];
    rendered->insertObservation(*inserted_scans[k], mrpt::poses::CPose3D(pose));
    rendered_poses.push_back(pose);
  }
  return *rendered;
}

common::OccupancyGrid RbpfMapper::map() const {
  common::OccupancyGrid grid;
  if (!impl_->started || impl_->inserted_scans.empty()) return grid;
  const mrpt::maps::COccupancyGridMap2D& mrpt_grid = impl_->publishedGrid();
  const int width = static_cast<int>(mrpt_grid.getSizeX()), height = static_cast<int>(mrpt_grid.getSizeY());
  grid.resolution = shortest(mrpt_grid.getResolution());
  grid.origin = common::Point2(shortest(mrpt_grid.getXMin()), shortest(mrpt_grid.getYMin()));
  grid.cells.create(height, width);
  for (int y = 0; y < height; ++y) {
    const int row = height - 1 - y;  // MRPT's row 0 is the bottom
    for (int x = 0; x < width; ++x) {
      const float free_probability = mrpt_grid.getCell(x, y);  // 0.5 exactly: never observed
      grid.cells(row, x) = free_probability == 0.5f
                               ? common::OccupancyGrid::kUnknown
                               : static_cast<int8_t>(std::lround(100.0 * (1.0 - free_probability)));
    }
  }
  return grid;
}

}  // namespace hidden_rooms::mapping
