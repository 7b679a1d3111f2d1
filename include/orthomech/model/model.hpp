#pragma once
// The Model: an immutable description of a mechanism (house style: never mutated by
// algorithms). It is built and validated once, by io/mechanism_file or by ModelBuilder in code.
//
// Free system (paper §2, docs/design.md §2). Coordinates q (size nq) and velocity parameters u
// (size n), q̇ = B̃(q) u (eq. (19)). Kinds of free system:
//   - planar rigid body: q = (x, y, φ) of the centre of mass and the body-frame angle, u = q̇,
//     M = diag(m, m, J_c);
//   - planar particle:   q = (x, y), u = q̇, M = diag(m, m).
// Interfaces never assume nq == n or a constant M (a Model can also hold a general system with
// M(q), model/general_system.hpp);
//   - spatial rigid body: q = (r, e), r the world position of the centre of mass and e a unit
//     quaternion (scalar first), u = (v, ω) with v = ṙ and ω the body-frame angular velocity,
//     q̇ = B̃u with B̃ = blockdiag(I₃, ½G(e)ᵀ), M = diag(m I₃, J) (docs/spatial.md §1; nq 7, n 6).
// A model is all planar (dimension 2) or all spatial (dimension 3).
// See model/free_system.hpp and model/spatial.hpp.
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "orthomech/error.hpp"

namespace orthomech {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Vector4d;  // quaternion (e0, e1, e2, e3), scalar first, Hamilton product

inline constexpr int kGround = -1;  // body index of the ground (fixed frame = world frame)

enum class BodyKind { rigid, particle, spatial };

// The layout of a kind's coordinates: nq entries of q; nu velocity parameters, the translations
// first, then the rotations (model/body_kinds.hpp defines each kind).
struct BodyLayout {
  int nq, nu, translations, rotations;
};
[[nodiscard]] constexpr BodyLayout body_layout(BodyKind kind) {
  switch (kind) {
    case BodyKind::rigid:
      return {3, 3, 2, 1};  // (x, y, φ)
    case BodyKind::particle:
      return {2, 2, 2, 0};  // (x, y)
    case BodyKind::spatial:
      break;
  }
  return {7, 6, 3, 3};  // q = (r, e), u = (v, ω)
}

// What a spatial body (BodyKind::spatial) adds: its frame, inertia and points in three dimensions.
struct SpatialBodyData {
  Mat3 inertia = Mat3::Identity();      // kg·m², about the centre of mass, body axes (symmetric)
  Vec3 com_local = Vec3::Zero();        // centre of mass in the body frame, m
  Vec3 design_position = Vec3::Zero();  // body frame origin in world at the design position, m
  Quat design_orientation{1, 0, 0, 0};  // body frame in world at the design position (unit)
  std::vector<std::pair<std::string, Vec3>> points;  // named points, body frame, m
};

struct Body {
  std::string name;
  BodyKind kind = BodyKind::rigid;
  double mass = 0.0;                // kg
  double inertia = 0.0;             // kg·m² about the centre of mass (rigid only)
  Vec2 com_local = Vec2::Zero();    // centre of mass in the body frame, m
  Vec3 design_pose = Vec3::Zero();  // body frame in world at the design position: x, y, angle
  std::vector<std::pair<std::string, Vec2>> points;  // named points, body frame, m
  std::vector<Vec2> outline;                         // drawing only, body frame
  int q_offset = 0;                                  // first coordinate of this body in q
  int u_offset = 0;                                  // first velocity parameter of this body in u
  SourceLocation where;
  SpatialBodyData spatial;  // BodyKind::spatial only (the planar fields above are then unused)
  [[nodiscard]] int nq() const { return body_layout(kind).nq; }
  [[nodiscard]] int nu() const { return body_layout(kind).nu; }
  // u's translation components (2 planar, 3 spatial), then its rotation components (0, 1, 3).
  [[nodiscard]] int translations() const { return body_layout(kind).translations; }
  [[nodiscard]] int rotations() const { return body_layout(kind).rotations; }
};

// A point fixed on a body (or on the ground). s is measured from the centre of mass, in the body
// frame (for the ground: the world position).
struct PointRef {
  int body = kGround;
  Vec2 s = Vec2::Zero();
  std::string label;  // "body.point" as written by the user
};

// A point fixed on a spatial body (or the ground): s from the centre of mass, body frame (for the
// ground: the world position).
struct SpatialPointRef {
  int body = kGround;
  Vec3 s = Vec3::Zero();
  std::string label;
};

// ---- Joints (docs/design.md §3). Each supplies f (eq. (20)), Eᵀ (eq. (23)) and Dᵀ (eq. (76)). ---
// Sign convention: λ of a joint is the force (and moment) that body j exerts on body i, in the
// world frame, for f = (point on i) − (point on j). docs/notation.md.
struct Revolute {  // rows: x, y.  f = r_i + R_i s_i − r_j − R_j s_j
  PointRef pi, pj;
};
struct Prismatic {  // rows: n, angle.  f = (nᵀ(r_Pj − r_Pi), φ_j − φ_i − φ0)
  PointRef pi, pj;
  Vec2 axis_local = Vec2::UnitX();  // slide direction, body i frame, unit
  double phi0 = 0.0;
};
struct Fixed {  // rows: x, y, angle.  f = (r_Pi − r_Pj, φ_j − φ_i − φ0)
  PointRef pi, pj;
  double phi0 = 0.0;
};
struct PinInSlot {  // rows: n.  Point Pj of body j on the line through Pi of body i along axis.
  PointRef pi, pj;
  Vec2 axis_local = Vec2::UnitX();
};
struct GearPair {  // rows: ratio.  f = (φ_j − φ_c) − k (φ_i − φ_c) − c0, c = carrier
  int bi = kGround, bj = kGround, carrier = kGround;
  double ratio = 1.0;
  double c0 = 0.0;
};
struct Distance {  // rows: length.  f = (|r_Pj − r_Pi|² − L²) / (2L): a massless pin-ended rod
  PointRef pi, pj;
  double length = 1.0;
};
// Spatial joints (docs/spatial.md §2.4): every type is a list of rows built from the primitives of
// constraints/spatial_joints.hpp (point components, dot-1, dot-2, distance, twist angle); the
// table of rows per type is defined there, in one place. Body i is the first of `connects`.
enum class SpatialJointType {
  spherical,
  revolute,
  cylindrical,
  prismatic,
  fixed,
  universal,
  planar,
  point_on_line,
  point_on_plane,
  distance,
  screw
};
struct SpatialJoint {
  SpatialJointType type = SpatialJointType::spherical;
  SpatialPointRef pi, pj;
  // The joint frame (columns f, g, h; h the axis) in body i's frame and in body j's frame: the
  // same world frame at the design position (docs/spatial.md §2.5). Universal: pin 1 = f of
  // frame_i, pin 2 = g of frame_j.
  Mat3 frame_i = Mat3::Identity();
  Mat3 frame_j = Mat3::Identity();
  // Reference direction of body j for the joint angle (revolute, cylindrical, screw): the angle is
  // the (P5) twist angle of ref_j about h_i from f_i (0 when ref_j lies along f_i).
  Vec3 ref_j = Vec3::UnitX();
  double pitch = 0.0;   // screw: axial advance per turn, m
  double length = 0.0;  // distance: m
};
using JointKind =
    std::variant<Revolute, Prismatic, Fixed, PinInSlot, GearPair, Distance, SpatialJoint>;

// Coulomb friction of a joint (`friction:` in the file; planar revolute joints so far): a
// friction moment μ r |F| on the pin, F the joint's force, r the pin radius, against the relative
// rotation (analysis/friction.hpp).
struct JointFriction {
  double coefficient = 0.0;  // μ (kinetic)
  double radius = 0.0;       // r, m
};

struct Joint {
  std::string name;
  JointKind kind;
  int row_offset = 0;  // first row of this joint in f, Eᵀ, Dᵀ
  // Range [min, max] of the joint coordinate (revolute: φ_j − φ_i, rad; prismatic: slide, m),
  // from `limits:` in the file; bounds of `assemble` (analysis/assembly.hpp).
  std::optional<Vec2> limits;
  // End stops at the limits (`end_stops: {restitution: e}`): simulate's motion meets them as
  // impacts, the approach speed reversed and multiplied by e ∈ [0, 1] (dynamics/events.hpp).
  std::optional<double> stop_restitution;
  std::optional<JointFriction> friction;
  SourceLocation where;
  [[nodiscard]] int rows() const;
  [[nodiscard]] std::string type_name() const;
  [[nodiscard]] std::vector<std::string> component_names() const;  // e.g. {"x", "y"}
};

// ---- Nonholonomic constraints (docs/design.md §3): Eᵀ rows only, no geometric residual. ---------
// Knife edge (Chaplygin sled): the point `at` of a rigid body cannot move across the blade,
// whose direction is axis_local in the body frame: nᵀ v_P = 0 with n = R(φ) perp(axis). One row;
// f = 0 (positions are never corrected along it); λ is the lateral force of the ground on the
// body at the point, along n.
struct KnifeEdge {
  std::string name;
  PointRef at;
  Vec2 axis_local = Vec2::UnitX();
  int row_offset = 0;  // its row in Eᵀ (after every joint's rows)
  SourceLocation where;
};

// Rolling disc (docs/spatial.md §3): a thin disc of a spatial body rolls without slipping on a
// fixed plane (point O, unit normal k; tangents t1, t2 = k × t1). With a = R axis_local, c = k·a,
// s = √(1 − c²), m = (k − c a)/s and ρ_P = R centre_local − radius·m (contact point P from the
// centre of mass): the disc's material point at P has zero velocity, nᵀ(v + w × ρ_P) = 0 for
// n = t1, t2 (nonholonomic, f = 0) and n = k (holonomic: f = k·(r_C − O) − radius·s, the height
// of the lowest rim point, corrected with the joints). λ of the three rows, named t1, t2, n, is the
// contact force of the ground on the disc at P: friction along t1, t2 and the normal force.
// Rows in constraints/rolling_disc.hpp.
struct RollingDisc {
  std::string name;
  int body = kGround;                // a spatial moving body
  double radius = 0.0;               // m, > 0
  Vec3 axis_local = Vec3::UnitZ();   // symmetry axis, body frame, unit
  Vec3 centre_local = Vec3::Zero();  // disc centre from the centre of mass, body frame
  Vec3 plane_point = Vec3::Zero();   // O, world
  Vec3 normal = Vec3::UnitZ();       // k, world, unit
  Vec3 t1 = Vec3::UnitX();           // world, unit, ⟂ k
  int row_offset = 0;                // its rows t1, t2, n in Eᵀ (after the knife edges')
  SourceLocation where;
};

// ---- Loads (docs/design.md §9). Each gives a generalized force Q (eq. (8)). ---------------------
struct Gravity {
  Vec2 g = Vec2(0.0, -9.81);
};
// Scalar function of a measure, by linear interpolation in a table (e.g. gas force vs stroke);
// constant when the table is empty.
// A table over an angle measure (unit rad) wraps with the turn by default: the measure is taken
// modulo 2π into [x_0, x_0 + 2π) before the look-up (`wrap: false` in the file turns it off).
struct Table {
  int measure = -1;
  std::vector<std::pair<double, double>> points;  // (measure value, factor), sorted
  bool wrap = false;                              // periodic in 2π (angle measures by default)
};
// A load that acts only while a measure's velocity has a sign (`active_while` in the file), e.g.
// a process force on the down-stroke only. measure < 0: always active.
struct ActiveWhile {
  int measure = -1;  // a position measure (derivative 0)
  int sign = 0;      // +1: while its rate is > 0; −1: while < 0
};
struct PointForce {  // force at a point: world or body-fixed direction, magnitude × table factor
  PointRef at;
  Vec2 force = Vec2::Zero();
  bool body_fixed = false;
  Table table;
};
struct Torque {
  int body = kGround;
  double torque = 0.0;
  Table table;
};
struct SpringDamper {  // tension T = k (L − L0) + c L̇ between two points
  PointRef pi, pj;
  double stiffness = 0.0, free_length = 0.0, damping = 0.0;
};
struct RotarySpringDamper {  // moment T = k (φ_j − φ_i − θ0) + c (φ̇_j − φ̇_i), acting on j (−) and i
                             // (+)
  int bi = kGround, bj = kGround;
  double stiffness = 0.0, free_angle = 0.0, damping = 0.0;
};
// Spatial loads (docs/spatial.md §1.4, §5): Q = (F_world, n_body) per body.
struct SpatialGravity {
  Vec3 g = Vec3(0.0, 0.0, -9.81);
};
struct SpatialPointForce {  // force at a point, world or body-fixed components, × table factor
  SpatialPointRef at;
  Vec3 force = Vec3::Zero();
  bool body_fixed = false;
  Table table;
};
struct SpatialTorque {  // pure moment on a body, world or body-fixed components, × table factor
  int body = kGround;
  Vec3 torque = Vec3::Zero();
  bool body_fixed = false;
  Table table;
};
struct SpatialSpringDamper {  // tension T = k (L − L0) + c L̇ between two points
  SpatialPointRef pi, pj;
  double stiffness = 0.0, free_length = 0.0, damping = 0.0;
};
struct JointSpringDamper {  // moment k (θ − θ0) + c θ̇ on a spatial revolute's angle θ
  int joint = -1;
  double stiffness = 0.0, free_angle = 0.0, damping = 0.0;
};
using LoadKind =
    std::variant<Gravity, PointForce, Torque, SpringDamper, RotarySpringDamper, SpatialGravity,
                 SpatialPointForce, SpatialTorque, SpatialSpringDamper, JointSpringDamper>;
struct Load {
  std::string name;
  LoadKind kind;
  SourceLocation where;
  ActiveWhile active_while = {};  // force and torque loads only
};

// ---- Measures: scalar functions s(q) of position, with derivative order 0/1/2. ---------------
struct JointCoordinate {  // revolute: φ_j − φ_i; prismatic: axisᵀ(r_Pj − r_Pi)
  int joint = -1;
};
struct PointCoordinate {  // world x or y of a point
  PointRef point;
  int axis = 0;
};
struct PointDistance {
  PointRef pi, pj;
};
struct BodyAngle {  // φ_j − φ_i (absolute body angle when bi is the ground)
  int bi = kGround, bj = kGround;
};
struct SpatialPointCoordinate {  // world x, y or z of a point
  SpatialPointRef point;
  int axis = 0;
};
struct SpatialPointDistance {
  SpatialPointRef pi, pj;
};
struct VectorAngle {  // angle between a vector fixed in body i and one fixed in body j, [0, π]
  int bi = kGround, bj = kGround;
  Vec3 ai = Vec3::UnitX(), aj = Vec3::UnitX();  // unit, in each body's frame
};
// Camber or toe of a wheel whose outboard spin axis a is fixed in `body` (s = R a in world;
// vehicle axes x forward, z up, docs/file-format.md): camber = −asin(s_z) (> 0: the top of the
// wheel leans outboard), toe = atan2(s_x, |s_y|) (> 0: toe-in, either side of the vehicle).
struct WheelAngle {
  enum class Which { camber, toe };
  int body = kGround;
  Vec3 axis = Vec3::UnitY();  // unit, body frame
  Which which = Which::camber;
};
using MeasureKind =
    std::variant<JointCoordinate, PointCoordinate, PointDistance, BodyAngle, SpatialPointCoordinate,
                 SpatialPointDistance, VectorAngle, WheelAngle>;
struct Measure {
  std::string name;
  MeasureKind kind;
  int derivative = 0;  // 0 position, 1 velocity, 2 acceleration
  std::string unit;    // SI unit of the reported value
  SourceLocation where;
};

// ---- Drivers: a prescribed input (a joint coordinate), docs/design.md §6. -----------------------
enum class Profile { constant_speed, harmonic, polynomial };
struct Driver {
  std::string name;
  int joint = -1;
  Profile profile = Profile::constant_speed;
  double speed = 0.0;                       // rad/s or m/s (constant_speed)
  double initial = 0.0;                     // input value at t = 0 (rad or m)
  double amplitude = 0.0, frequency = 0.0;  // harmonic: s0 + a sin(2π f t)
  std::vector<double> coefficients;         // polynomial: s(t) = Σ c_k t^k
  SourceLocation where;
};

// ---- Design positions (validated by `validate`). -------------------------------------------
struct DesignTarget {
  PointRef point;
  Vec2 position = Vec2::Zero();
  std::optional<double> angle;  // body angle target (motion generation)
  double tolerance = 1e-3;
  // Dimension 3 (the planar fields above are then unused): the point, its world position (m) and
  // optionally the orientation of the point's body: the whole body frame in world, or one body
  // axis (body frame, unit) along a world direction (unit). angle_tolerance: rad (none: the
  // planar rule, tolerance / L).
  SpatialPointRef spatial_point;
  Vec3 spatial_position = Vec3::Zero();
  std::optional<Quat> orientation;
  std::optional<std::pair<Vec3, Vec3>> direction;  // (body axis, world direction)
  std::optional<double> angle_tolerance;
};
struct DesignPosition {
  std::string name;
  std::vector<std::pair<int, double>> inputs;  // (joint index, value in SI)
  std::optional<DesignTarget> target;
  SourceLocation where;
};

// ---- Initial velocities (file section `initial`; used by simulate). -----------------------
// The rate at t = 0 of a measure's position quantity (a joint coordinate, a point coordinate, a
// distance, a body angle), SI (m/s or rad/s). simulate makes the velocity admissible and fits
// these rates by least squares in the chart coordinates (dynamics/simulate.hpp).
struct InitialRateSpec {
  int measure = -1;  // index into Model::measures
  double rate = 0.0;
  SourceLocation where;
};
struct InitialConditions {
  std::vector<InitialRateSpec> rates;
};

struct GeneralSystem;  // model/general_system.hpp

// The units a file declares (`units:`), by name (docs/file-format.md); every value in the Model is
// SI. Outputs use them by default (io/units.hpp: UnitSystem).
struct DeclaredUnits {
  std::string length = "m", angle = "rad", mass = "kg", time = "s", force = "N";
};

struct AnalysisDefaults {
  int steps = 360;
  std::string driver;
};

// The whole mechanism. Build with ModelBuilder (validates and assigns offsets), then treat as
// immutable: every algorithm takes `const Model&`.
struct Model {
  std::string name;
  std::string description;
  std::string file;          // where it came from (for messages)
  std::vector<Body> bodies;  // moving bodies only; the ground is implicit (kGround)
  std::vector<Joint> joints;
  std::vector<KnifeEdge> knife_edges;      // nonholonomic rows, after the joints' rows
  std::vector<RollingDisc> rolling_discs;  // three rows each, after the knife edges' rows
  std::vector<Load> loads;
  std::vector<Measure> measures;
  std::vector<Driver> drivers;
  std::vector<DesignPosition> design_positions;
  AnalysisDefaults analysis;
  DeclaredUnits units;                // as declared by the file (SI when built in code)
  std::vector<std::string> warnings;  // "file:line:col: warning: element: message", from loading
  InitialConditions initial;          // initial velocities of simulate (may be empty: at rest)
  // Set by make_general_model (model/general_system.hpp): a free system given by functions,
  // with M(q), instead of bodies, joints and loads (which are then empty).
  std::shared_ptr<const GeneralSystem> general;
  int dimension = 2;  // 2: planar bodies and joints; 3: spatial bodies and joints
  int nq = 0;         // number of coordinates
  int n = 0;          // number of velocity parameters (free system DOF), eq. (25)
  int nc = 0;         // number of constraint equations (rows of Eᵀ), eq. (22)

  [[nodiscard]] std::string body_name(int b) const {
    return b == kGround ? std::string("ground") : bodies[static_cast<size_t>(b)].name;
  }
  [[nodiscard]] int find_body(const std::string& name) const;   // kGround for "ground", -2 if none
  [[nodiscard]] int find_joint(const std::string& name) const;  // -1 if none
  [[nodiscard]] int find_measure(const std::string& name) const;
  [[nodiscard]] VecX design_q() const;  // q of the design poses (not necessarily assembled)
  // "joint 'D', y": the user's name for constraint row k.
  [[nodiscard]] std::string constraint_row_name(int row) const;
};

// Assigns coordinate and row offsets and computes nq, n, nc; checks indices. Call after the
// vectors of a Model are filled (the file reader does); throws std::invalid_argument on misuse.
void finalize_model(Model& model);

}  // namespace orthomech
