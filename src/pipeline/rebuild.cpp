// The rebuilds of a LoD2 model (explain_more, rebuild.hpp).
#include "pipeline/rebuild.hpp"

#include <algorithm>
#include <optional>
#include <sstream>
#include <string>

#include "city3d/error.hpp"
#include "city3d/evaluation.hpp"
#include "city3d/log.hpp"
#include "city3d/rings.hpp"
#include "city3d/stage_profile.hpp"
#include "pipeline/outline.hpp"

namespace city3d::detail {
namespace {

std::string percent(std::size_t part, std::size_t whole) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 100.0 * static_cast<double>(part) / static_cast<double>(whole) << "%";
  return s.str();
}

// A parameter's value as the notes name it: 4 for 4.0, 4.5 for 4.5.
std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Whether two hypotheses give the same model under the same selection parameters: the same
// candidate faces (vertices, faces) and the same selection problem, exactly. explain_more's variants
// often rebuild the rung's own hypothesis (smaller planes that find no new plane, a wide outline
// that closes no gap): their selections would only repeat ones already made.
bool same_hypothesis(const Lod2Hypothesis& a, const Lod2Hypothesis& b) {
  if (a.parts.size() != b.parts.size() || a.part_numbers != b.part_numbers) return false;
  const auto same_face = [](const CandidateFace& f, const CandidateFace& g) {
    return f.kind == g.kind && f.source == g.source && f.plane_id == g.plane_id && f.cell_or_edge == g.cell_or_edge &&
           f.vertices == g.vertices && f.area == g.area;
  };
  const auto same_edge = [](const SelectionProblem::Edge& e, const SelectionProblem::Edge& d) {
    return e.faces == d.faces && e.sharp_pairs == d.sharp_pairs;
  };
  for (std::size_t k = 0; k < a.parts.size(); ++k) {
    const CandidateFaces &x = a.parts[k], &y = b.parts[k];
    if (!std::equal(x.vertices.begin(), x.vertices.end(), y.vertices.begin(), y.vertices.end(), same_point) ||
        !std::equal(x.faces.begin(), x.faces.end(), y.faces.begin(), y.faces.end(), same_face))
      return false;
    const SelectionProblem &p = x.problem, &q = y.problem;
    if (p.face_count != q.face_count || p.support != q.support || p.centroid_z != q.centroid_z ||
        p.is_roof != q.is_roof || p.unsupported != q.unsupported || p.plan_area != q.plan_area ||
        p.point_count != q.point_count || p.z_min != q.z_min || p.z_max != q.z_max ||
        !std::equal(p.edges.begin(), p.edges.end(), q.edges.begin(), q.edges.end(), same_edge) ||
        p.vertical_overlaps != q.vertical_overlaps || p.exactly_one != q.exactly_one ||
        p.face_prior != q.face_prior || p.forced_on != q.forced_on || p.forced_off != q.forced_off ||
        p.start != q.start)
      return false;
  }
  return true;
}

// Whether two models are the same, exactly: vertices, faces and their surface types.
bool same_model(const BuildingModel& a, const BuildingModel& b) {
  return a.mesh.faces == b.mesh.faces && a.surfaces == b.surfaces &&
         std::equal(a.mesh.vertices.begin(), a.mesh.vertices.end(), b.mesh.vertices.begin(),
                    b.mesh.vertices.end(), same_point);
}

}  // namespace

ModelFit explain_more(const BuildingInput& input, const ReconstructionParams& params, const Lod2Rung& rung,
                       BuildingReport& r, BuildingModel& model) {
  const Lod2Hypothesis& hypothesis = rung.hypothesis;
  const Clock::time_point deadline = rung.deadline;
  const std::size_t n = input.points.size();
  if (n == 0) return {};
  const SurfaceSupportParams& support_params = params.hypothesis.surface_support;
  std::optional<StageTimer> measuring(Stage::measure);
  const LocalTop local_top(input.points, support_params.radius);
  measuring.reset();
  const auto fit = [&](const BuildingModel& m, std::vector<double>* distances) {
    const StageTimer stage(Stage::measure);
    return fit_both_ways(m.mesh, surface_types(m), input.points, local_top, support_params, distances);
  };
  std::vector<double> distances;
  ModelFit best = fit(model, &distances);
  const bool too_many_left_out = static_cast<double>(best.far) > params.retry_unexplained_share * static_cast<double>(n);
  const bool unsupported = best.support.unsupported_area > params.retry_unsupported_area;
  if (!too_many_left_out && !unsupported) return best;
  std::vector<bool> unexplained = points_beneath_unsupported(best.support, input.points, support_params);
  for (std::size_t i = 0; i < n; ++i) unexplained[i] = unexplained[i] || distances[i] > kUnexplainedDistance;
  const double area = r.footprint_area;  // of input.footprint.polygons (describe_points)
  const double density = area > 0.0 ? static_cast<double>(n) / area : 0.0;
  const auto what = [&](const ModelFit& e) {
    std::string text;
    if (too_many_left_out) text = "unexplained points " + percent(e.far, n);
    if (unsupported) {
      std::ostringstream s;
      s.precision(1);
      s << std::fixed << e.support.unsupported_area << " m2";
      text += (text.empty() ? "" : ", ") + std::string("unsupported surface ") + s.str();
    }
    return text;
  };
  const auto candidate_faces = [](const Lod2Hypothesis& h) {
    std::size_t faces = 0;
    for (const CandidateFaces& part : h.parts) faces += part.faces.size();
    return faces;
  };
  const std::size_t faces = candidate_faces(hypothesis);
  const RebuildScope rebuilding;  // from here on, the stages count as the rebuild's
  RebuildOutcome outcome;
  outcome.unexplained = too_many_left_out;
  outcome.unsupported = unsupported;
  outcome.far_before = outcome.far_after = best.far;
  outcome.unsupported_before = outcome.unsupported_after = best.support.unsupported_area;
  // A work limit (RebuildParams::max_candidate_faces): a building whose hypothesis has more candidate
  // faces is not rebuilt, and a variant hypothesis with more is not selected. Each rebuild is a
  // selection at least as large as the rung's, and the smaller planes make larger programs: the two
  // 40,000-point clouds of city3d_dev (8,312 and 13,874 candidate faces) took 521 s and 110 s with
  // their rebuilds, against 14 s and 10 s without, and AHN3/13894's smaller planes turned 1,933
  // candidate faces into 5,852 and 1 s into 38 s (docs/BENCHMARKS.md).
  const std::size_t max_faces = params.rebuild.max_candidate_faces;
  if (faces > max_faces) {
    outcome.result = RebuildOutcome::Result::too_large;
    r.rebuild = outcome;
    add_note(r, what(best) + ": not rebuilt (" + std::to_string(faces) + " candidate faces, more than " +
                    std::to_string(max_faces) + ")");
    return best;
  }
  const int small_points = std::max<int>(params.planes.small_min_points, params.planes.min_points / 2);
  struct HypothesisVariant {
    bool smaller_planes;
    bool wide_outline;
    bool left_out;
  };
  std::vector<HypothesisVariant> hypotheses{{false, false, false}};
  if (small_points < params.planes.min_points) hypotheses.push_back({true, false, false});
  if (!input.footprint_given) {
    hypotheses.push_back({false, true, false});
    if (small_points < params.planes.min_points) hypotheses.push_back({true, true, false});
  }
  hypotheses.push_back({false, false, true});
  struct SelectionVariant {
    bool without_prior;
    bool half_complexity;
  };
  const SelectionVariant selections[] = {{false, false}, {true, false}, {false, true}, {true, true}};
  const auto variant_of = [](const HypothesisVariant& h, const SelectionVariant& v) {
    return RebuildOutcome::Variant{h.smaller_planes, h.wide_outline, h.left_out, v.without_prior, v.half_complexity};
  };
  const auto name = [&](const HypothesisVariant& h, const SelectionVariant& v) {
    std::string text;
    const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
    if (h.smaller_planes) add("roof planes of at least " + std::to_string(small_points) + " points");
    if (h.left_out) add("roofs for the points left out");
    if (h.wide_outline)
      add("an outline closing gaps of " + number_text(params.outline.wide_gap_spacings) + " point spacings");
    if (v.without_prior) add("without the face prior");
    if (v.half_complexity) add("half the complexity weight");
    return text;
  };

  std::vector<Lod2Hypothesis> tried;  // the variant hypotheses selected over (the rung's own is `hypothesis`)
  std::vector<BuildingModel> selected{rung.selected};  // the models the selections gave, as they gave them
  const ModelFit before = best;
  std::string kept;
  std::string over_limit;  // variant hypotheses not selected: more than max_faces candidate faces
  BuildingReport kept_report;
  // The opt-in --time-limit bounds the rebuilds too: once it is used up no further variant is begun,
  // and the best model so far is kept.
  const auto out_of_time = [&] { return deadline != Clock::time_point::max() && Clock::now() > deadline; };
  bool stopped = false;
  for (const HypothesisVariant& h : hypotheses) {
    if ((stopped = stopped || out_of_time())) break;
    const bool own = !h.smaller_planes && !h.wide_outline && !h.left_out;
    ReconstructionParams hp = params;
    if (h.smaller_planes) hp.planes.min_points = small_points;
    BuildingReport after_hypothesis = own ? rung.before_selection : rung.before_hypothesis;
    std::optional<Lod2Hypothesis> built;
    if (!own) {
      try {
        const Lod2Variant variant{rung.footprint_walls_only, h.wide_outline, h.left_out ? &unexplained : nullptr,
                                  &hypothesis.raster};
        built = lod2_hypothesis(input, hp, variant, deadline, nullptr, after_hypothesis);
      } catch (const Error& e) {
        log_debug("explain: building " + input.id + ": " + name(h, {}) + ": " + e.what());
        continue;
      }
      if (candidate_faces(*built) > max_faces) {
        over_limit += (over_limit.empty() ? "" : ", ") + name(h, {}) + ": " + std::to_string(candidate_faces(*built));
        outcome.over_limit.emplace_back(variant_of(h, {}), candidate_faces(*built));
        continue;
      }
      // A hypothesis already selected over gives the same models again: none could be kept.
      if (same_hypothesis(*built, hypothesis) ||
          std::any_of(tried.begin(), tried.end(), [&](const Lod2Hypothesis& t) { return same_hypothesis(*built, t); })) {
        log_debug("explain: building " + input.id + ": " + name(h, {}) + ": the same hypothesis as one tried");
        continue;
      }
    }
    // Selections with the prior that had to drop it equal those without: those are skipped.
    bool prior_dropped = own && rung.without_prior;
    for (const SelectionVariant& v : selections) {
      if ((stopped = out_of_time())) break;
      if (own && !v.without_prior && !v.half_complexity) continue;  // the rung's own model
      // Surface no point supports, with the points explained, is a matter of the hypothesis (a part
      // too small for a plane, a roof level missing): the selections that explain more points (without
      // the face prior, half the complexity weight) are not tried for it.
      if (!too_many_left_out && (v.without_prior || v.half_complexity)) continue;
      if (v.without_prior && prior_dropped) continue;
      ReconstructionParams p = hp;
      if (v.without_prior) p.selection.use_face_prior = false;
      if (v.half_complexity) p.selection.lambda_complexity /= 2;
      BuildingReport trial = after_hypothesis;
      try {
        bool dropped = false;
        BuildingModel raw =
            lod2_model(input, own ? hypothesis : *built, p, deadline, nullptr, trial, &dropped);
        if (!v.without_prior && !v.half_complexity) prior_dropped = dropped;
        // A model already measured was kept, or was no better than the model then kept: it cannot be
        // better than `best`, which only got better since.
        if (std::any_of(selected.begin(), selected.end(),
                        [&](const BuildingModel& s) { return same_model(s, raw); })) {
          log_debug("explain: building " + input.id + ": " + name(h, v) + ": the same model as one measured");
          continue;
        }
        selected.push_back(raw);
        BuildingModel m =
            checked_model(p, rung.level, rung.footprint_walls_only, std::move(raw), nullptr, trial);
        ModelFit e = fit(m, nullptr);
        if (e.unfaithful(density) < best.unfaithful(density) &&
            e.squares_both_ways(density) < best.squares_both_ways(density)) {
          best = std::move(e);
          model = std::move(m);
          kept = name(h, v);
          outcome.variant = variant_of(h, v);
          kept_report = std::move(trial);
        }
      } catch (const Error& e) {
        // A variant that cannot be built leaves the model as it was.
        log_debug("explain: building " + input.id + ": " + name(h, v) + ": " + e.what());
      }
    }
    if (built) tried.push_back(std::move(*built));
  }
  outcome.stopped = stopped;
  outcome.far_after = best.far;
  outcome.unsupported_after = best.support.unsupported_area;
  outcome.result = kept.empty() ? RebuildOutcome::Result::no_better : RebuildOutcome::Result::rebuilt;
  if (!kept.empty()) {
    r = std::move(kept_report);
    std::string change;
    if (too_many_left_out) change = "unexplained points " + percent(before.far, n) + " -> " + percent(best.far, n);
    if (unsupported) {
      std::ostringstream s;
      s.precision(1);
      s << std::fixed << "unsupported surface " << before.support.unsupported_area << " -> "
        << best.support.unsupported_area << " m2";
      change += (change.empty() ? "" : ", ") + s.str();
    }
    add_note(r, "rebuilt (" + kept + "): " + change);
  } else {
    add_note(r, what(before) + ": no rebuild explained more");
  }
  if (!over_limit.empty())
    add_note(r, "not tried (more than " + std::to_string(max_faces) + " candidate faces): " + over_limit);
  if (stopped) add_note(r, "rebuilds stopped at the time limit");
  r.rebuild = std::move(outcome);
  return best;
}

}  // namespace city3d::detail
