#include "orthomech/analysis/shaking.hpp"

#include <cstddef>
#include <string>
#include <utility>

#include "orthomech/check.hpp"
#include "orthomech/model/body_kinds.hpp"

namespace orthomech {

MomentumRate momentum_rate(const Model& model, const VecX& q, const VecX& u, const VecX& udot,
                           const Vec3& about) {
  check_argument(q.size() == model.nq && u.size() == model.n && udot.size() == model.n,
                 "momentum_rate", "state", "q, u and u̇ must have the model's sizes");
  MomentumRate rate;
  for (const Body& b : model.bodies)
    visit_kind(b, [&](auto kind) {
      decltype(kind)::add_momentum_rate(b, q, u, udot, about, rate.linear, rate.angular);
    });
  return rate;
}

ShakingSeries shaking_series(const Model& model, const CycleResult& result, const Vec3& about) {
  ShakingSeries s;
  s.about = about;
  const std::size_t n = result.points.size();
  s.force.assign(n, Vec3::Zero());
  s.moment.assign(n, Vec3::Zero());
  s.reported.assign(n, false);
  VecX q(model.nq), u(model.n), udot(model.n);
  for (std::size_t k = 0; k < n; ++k) {
    const DrivenPointView p = result.points[k];
    if (!rates_reported(p)) continue;
    q = p.q;
    u = p.u;
    udot = p.udot;
    const MomentumRate rate = momentum_rate(model, q, u, udot, about);
    s.force[k] = -rate.linear;    // F_s = −Ṗ
    s.moment[k] = -rate.angular;  // M_s = −Ḣ_O
    s.reported[k] = true;
  }
  return s;
}

ShakingSummaries summarize_shaking(const Model& model, const CycleResult& result,
                                   const ShakingSeries& series) {
  ShakingSummaries out;
  const bool planar = model.dimension == 2;
  const std::size_t n = series.force.size();
  std::vector<double> v(n);
  auto add = [&](std::vector<SeriesSummary>& list, std::string name, const char* unit, auto value) {
    for (std::size_t k = 0; k < n; ++k) v[k] = value(k);
    list.push_back(summarize_values(result, std::move(name), unit, v, series.reported));
  };
  add(out.magnitudes, "shaking force", "N", [&](std::size_t k) { return series.force[k].norm(); });
  add(out.magnitudes, "shaking moment", "N*m",
      [&](std::size_t k) { return planar ? series.moment[k].z() : series.moment[k].norm(); });
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i < (planar ? 2 : 3); ++i)
    add(out.components, std::string("shaking force ") + axes[i], "N",
        [&](std::size_t k) { return series.force[k](i); });
  if (!planar)
    for (int i = 0; i < 3; ++i)
      add(out.components, std::string("shaking moment ") + axes[i], "N*m",
          [&](std::size_t k) { return series.moment[k](i); });
  return out;
}

}  // namespace orthomech
