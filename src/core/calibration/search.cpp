#include "ladar_perception/calibration/search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace ladar_perception {
namespace calibration {

namespace {

// Counts evaluations and remembers the best hypothesis seen.
struct Evaluator {
  const CostFn& cost;
  SearchResult* result;
  double operator()(const Pose6& p) {
    const double c = cost(p);
    ++result->evaluations;
    if (std::isfinite(c) && c < result->best_cost) {
      result->best_cost = c;
      result->best = p;
    }
    return std::isfinite(c) ? c : std::numeric_limits<double>::max();
  }
};

bool report(const ProgressFn& progress, const char* stage, SearchResult* r, const Pose6& spread) {
  r->spread = spread;
  r->trace.push_back(r->best);
  if (!progress) return true;
  SearchProgress p;
  p.stage = stage;
  p.iteration = r->iterations;
  p.evaluations = r->evaluations;
  p.best_cost = r->best_cost;
  p.estimate = r->best;
  p.spread = spread;
  if (!progress(p)) {
    r->cancelled = true;
    return false;
  }
  return true;
}

bool belowAccuracy(const Pose6& spread, const SearchParams& params) {
  for (int i = 0; i < 6; ++i) {
    if (params.active[i] && spread[i] > params.min_spread[i]) return false;
  }
  return true;
}

SearchResult start(const CostFn& cost, const SearchParams& params) {
  SearchResult r;
  r.best = params.initial;
  r.best_cost = std::numeric_limits<double>::infinity();
  Evaluator eval{cost, &r};
  eval(params.initial);
  if (!std::isfinite(r.best_cost)) r.best_cost = std::numeric_limits<double>::max();
  r.weighted_mean = params.initial;
  return r;
}

// One descent at a fixed step vector; returns true when at least one step improved.
// Finite-difference gradient over the active DOFs with probes of `probe` * step, then a step of
// at most `step` per DOF along the steepest descent in the step-scaled metric.
bool descend(Evaluator& eval, SearchResult* r, const Pose6& step, const SearchParams& params,
             const ProgressFn& progress, const char* stage, int max_iterations) {
  bool improved_any = false;
  for (int it = 0; it < max_iterations; ++it) {
    const Pose6 x = r->best;
    const double f = r->best_cost;
    Pose6 scaled_grad = Pose6::Zero();
    for (int i = 0; i < 6; ++i) {
      if (!params.active[i] || step[i] <= 0) continue;
      const double h = params.gradient_probe * step[i];
      Pose6 xp = x, xm = x;
      xp[i] += h;
      xm[i] -= h;
      const double fp = eval(xp), fm = eval(xm);
      scaled_grad[i] = (fp - fm) / (2.0 * h) * step[i];  // gradient in units of the step
    }
    // The probes may themselves have improved the best; continue from there if so.
    const double norm = scaled_grad.cwiseAbs().maxCoeff();
    bool improved = r->best_cost < f;
    if (norm > 0) {
      Pose6 candidate = x;
      for (int i = 0; i < 6; ++i) candidate[i] -= scaled_grad[i] / norm * step[i];
      const double fc = eval(candidate);
      improved = improved || fc < f;
    }
    ++r->iterations;
    if (!report(progress, stage, r, step)) return improved_any;
    if (!improved) break;
    improved_any = true;
  }
  return improved_any;
}

}  // namespace

SearchResult gradientDescent(const CostFn& cost, const SearchParams& params,
                             const ProgressFn& progress) {
  SearchResult r = start(cost, params);
  Evaluator eval{cost, &r};
  // Fixed step: the accuracy wanted (the thesis's fixed-step variant, which needs a good start).
  const Pose6 step = params.min_spread.cwiseMax(params.spread * 0.05);
  descend(eval, &r, step, params, progress, "gradient", params.max_iterations * 10);
  r.weighted_mean = r.best;
  return r;
}

SearchResult multiScaleGradientDescent(const CostFn& cost, const SearchParams& params,
                                       const ProgressFn& progress) {
  SearchResult r = start(cost, params);
  Evaluator eval{cost, &r};
  Pose6 step = params.spread * 0.5;
  while (!r.cancelled && r.iterations < params.max_iterations * 10) {
    descend(eval, &r, step, params, progress, "gradient_multiscale", params.max_iterations);
    if (r.cancelled || belowAccuracy(step, params)) break;
    step *= 0.5;  // no step at this scale improves: go one scale finer
  }
  r.spread = step;
  r.weighted_mean = r.best;
  return r;
}

namespace {
// Exhaustive grid over the DOFs in `dofs` (active ones only) around the current best.
void gridPass(Evaluator& eval, SearchResult* r, const Pose6& range, const std::vector<int>& dofs,
              const SearchParams& params) {
  const int n = std::max(3, params.interval_steps | 1);
  std::vector<int> axes;
  for (int d : dofs) {
    if (params.active[d] && range[d] > 0) axes.push_back(d);
  }
  if (axes.empty()) return;
  const Pose6 centre = r->best;
  std::vector<int> counter(axes.size(), 0);
  while (true) {
    Pose6 h = centre;
    bool is_centre = true;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const double off = -range[axes[a]] + 2.0 * range[axes[a]] * counter[a] / (n - 1);
      h[axes[a]] += off;
      is_centre = is_centre && counter[a] == n / 2;
    }
    if (!is_centre) eval(h);
    std::size_t a = 0;
    while (a < axes.size() && ++counter[a] == n) counter[a++] = 0;
    if (a == axes.size()) break;
  }
}

// The interval searches (Algorithm 2 and its semi-independent variant): each iteration runs a
// grid pass over every group of axes in turn, then shrinks the range.
SearchResult groupedIntervalSearch(const CostFn& cost, const SearchParams& params,
                                   const ProgressFn& progress, const char* name,
                                   const std::vector<std::vector<int>>& axis_groups) {
  SearchResult r = start(cost, params);
  Evaluator eval{cost, &r};
  Pose6 range = params.spread;
  while (r.iterations < params.max_iterations) {
    for (const std::vector<int>& axes : axis_groups) gridPass(eval, &r, range, axes, params);
    ++r.iterations;
    range *= params.shrink;
    if (!report(progress, name, &r, range)) break;
    if (belowAccuracy(range, params)) break;
  }
  r.weighted_mean = r.best;
  return r;
}
}  // namespace

SearchResult intervalSearch(const CostFn& cost, const SearchParams& params,
                            const ProgressFn& progress) {
  return groupedIntervalSearch(cost, params, progress, "interval", {{0, 1, 2, 3, 4, 5}});
}

SearchResult semiIndependentIntervalSearch(const CostFn& cost, const SearchParams& params,
                                           const ProgressFn& progress) {
  // The sensitive axes (rotation) first, then translation.
  return groupedIntervalSearch(cost, params, progress, "semi_independent",
                               {{kRoll, kPitch, kYaw}, {kX, kY, kZ}});
}

SearchResult particleFilter(const CostFn& cost, const SearchParams& params,
                            const ProgressFn& progress) {
  SearchResult r = start(cost, params);
  Evaluator eval{cost, &r};
  std::mt19937_64 rng(params.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  struct Hyp {
    Pose6 pose;
    double cost;
  };
  std::vector<Hyp> centres{{params.initial, r.best_cost}};
  std::vector<Hyp> pool;
  const int n_centres = std::max(1, params.resampling_centres);
  const int per_step = std::max(1, params.particles_per_step);
  Pose6 sigma = params.spread;
  Pose6 weighted_sum = Pose6::Zero();
  double weight_total = 0;
  const auto accumulateWeight = [&](const Pose6& p, double c) {
    const double w = 1.0 / std::max(c, 1e-12);  // inverse-error weight
    weighted_sum += w * p;
    weight_total += w;
  };
  accumulateWeight(params.initial, r.best_cost);
  int stale = 0;
  while (r.iterations < params.max_iterations) {
    const double best_before = r.best_cost;
    pool = centres;
    for (int s = 0; s < per_step; ++s) {
      const Hyp& c = centres[s % centres.size()];
      Pose6 h = c.pose;
      for (int i = 0; i < 6; ++i) {
        if (params.active[i]) h[i] += sigma[i] * normal(rng);
      }
      const double e = eval(h);
      pool.push_back({h, e});
      accumulateWeight(h, e);
    }
    const std::size_t keep = std::min<std::size_t>(n_centres, pool.size());
    std::partial_sort(pool.begin(), pool.begin() + keep, pool.end(),
                      [](const Hyp& a, const Hyp& b) { return a.cost < b.cost; });
    centres.assign(pool.begin(), pool.begin() + keep);
    // Shrink each DOF's sigma from the spread of the best hypotheses.
    Pose6 mean = Pose6::Zero();
    for (const Hyp& h : centres) mean += h.pose;
    mean /= static_cast<double>(centres.size());
    Pose6 var = Pose6::Zero();
    for (const Hyp& h : centres) var += (h.pose - mean).cwiseAbs2();
    var /= static_cast<double>(centres.size());
    for (int i = 0; i < 6; ++i) {
      const double target = params.spread_gain * std::sqrt(var[i]);
      sigma[i] = std::min(sigma[i], std::max(sigma[i] * params.max_shrink, target));
    }
    ++r.iterations;
    r.weighted_mean = weighted_sum / weight_total;
    if (!report(progress, "particle_filter", &r, sigma)) break;
    if (belowAccuracy(sigma, params)) break;
    stale = r.best_cost < best_before ? 0 : stale + 1;
    if (params.patience > 0 && stale >= params.patience) break;
  }
  r.weighted_mean = weighted_sum / weight_total;
  return r;
}

}  // namespace calibration
}  // namespace ladar_perception
