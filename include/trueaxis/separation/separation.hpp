// trueaxis::separation — straightness error separation with displacement probes (JPH0464003B2;
// Whitehouse 1976).
//
// Physical model (library units: mm and rad). A carrier moving along x carries N probes at
// offsets s_i (mm, s_0 = 0) from probe A. At station K (x_K = x_0 + K·h) probe i reads
//
//     m_i(K) = w(x_K + s_i) + g(x_K) + s_i·θ(x_K) + o_i + noise,
//
// w: workpiece profile, g: guide straightness (carrier motion at probe A), θ: pitch, o_i: probe
// zero offsets. Probes that read the gap (reading falls when the surface rises) must be negated
// first (the CLI's --invert). An optional angle channel reads a(K) = θ(x_K) + o_a.
//
// Everything is defined only up to a straight line (w + a + b·x, g − a − b·x, θ − b), so results
// are always stated against a reference (Reference). With pitch modelled and no zero difference
// or angle channel, a parabola is also unobservable and must be fixed by convention.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace trueaxis::separation {

enum class Method {
  TwoPoint,    // A: sequential two-point (probes at 0, h; no pitch)
  ThreePoint,  // B: JPH0464003B2's sequential three-point with pitch (probes at 0, h, 2h)
  Lsq,         // C: least-squares multi-probe solver (any whole-step offsets, angle channel)
};

enum class Reference {
  LeastSquares,  // w and g are residuals from their own LS lines; θ about its mean
  Seed,          // three-point only: JPH0464003B2's X_0 = 0, α, β by least squares, θ_0 = 0
  MinZone,       // w and g relative to the middle line of their minimum zones; θ about its mean
};

const char* to_string(Method m);
const char* to_string(Reference r);
Method method_from_string(const std::string& s);        // "two-point" | "three-point" | "lsq"
Reference reference_from_string(const std::string& s);  // "ls" | "patent" | "min-zone"

// Probe readings. Units: mm and rad.
struct ProbeData {
  Eigen::VectorXd x;            // n station positions, strictly increasing with equal step h
  Eigen::MatrixXd readings;     // n x N probe readings (mm), column i = probe i
  std::vector<double> offsets;  // N probe offsets from probe A (mm); offsets[0] == 0; whole
                                // multiples of h; distinct
  Eigen::VectorXd angle;        // empty, or n pitch readings (rad)
  // True when nobody stated the offsets and a reader took them as 0, h, 2h, … (the stations'
  // step): the figures hold only if the probes really stand so, and the result says it.
  bool offsets_assumed = false;

  double step() const;
  // Throws Error with a plain message if the data break the preconditions above.
  void validate() const;
};

struct Options {
  Method method = Method::Lsq;
  Reference reference = Reference::LeastSquares;
  // Known zero difference e = Σ z_i·o_i of a three-probe layout (mm), with z chosen so that
  // z_A = 1 and z annihilates constants and s_i; for offsets 0, l, 2l: e = o_A − 2·o_B + o_C.
  // Removes the parabola ambiguity.
  std::optional<double> zero_difference;
  // Probe noise (standard deviation, mm). If absent, uncertainties are scaled by the residual
  // RMS (only possible when the data are redundant).
  std::optional<double> sigma;
  // Angle-channel noise (rad); weights the angle rows against the probes.
  double angle_sigma = 1e-6;
  // Probe noise assumed for weighting when `sigma` is absent (mm).
  double nominal_sigma = 1e-4;
  // If > 0: ISO 16610-21 Gaussian filter (cut-off, mm) applied to w and g after separation.
  // Uncertainties are then not reported.
  double filter_cutoff = 0;
  bool compute_uncertainty = true;

  void validate() const;
};

struct Profile {
  Eigen::VectorXd x;            // mm
  Eigen::VectorXd value;        // mm (w, g) or rad (pitch)
  Eigen::VectorXd uncertainty;  // standard uncertainty, same unit; empty if not computed
};

struct Straightness {
  double ls = 0;        // peak-to-valley about the least-squares line (mm)
  double min_zone = 0;  // minimum-zone width (mm)
  // Expanded uncertainty (95 % coverage) of the figure (mm): 2·z·max uᵢ with z = Φ⁻¹(1 −
  // 0.025/n) over the profile's n points (Bonferroni: every point's error within z·uᵢ at once),
  // since a peak-to-valley is off by at most twice the largest point error. Absent when the result
  // states no uncertainty (see Result::no_uncertainty for why).
  std::optional<double> U;
  // Whether the data resolve the figure: U below the minimum-zone width (so below both
  // figures). Absent with U.
  std::optional<bool> resolved() const {
    if (!U) return std::nullopt;
    return *U < min_zone;
  }
};

struct Result {
  Method method = Method::Lsq;
  Reference reference = Reference::LeastSquares;
  Profile workpiece, guide;
  std::optional<Profile> pitch;
  Straightness workpiece_straightness, guide_straightness;
  std::vector<std::string> unobservable;  // modes the data cannot determine
  std::string gauge;                      // how they were fixed
  std::optional<double> sigma;            // probe noise behind the uncertainties (mm)
  bool sigma_estimated = false;
  // Why no uncertainty is stated, in words, when the profiles carry none ("noise-free input:
  // ..."); empty when they do.
  std::string no_uncertainty;
  long dof = 0;             // redundancy: equations − free unknowns
  double residual_rms = 0;  // RMS of weighted residuals (mm); 0 without redundancy
  // When no noise level is known (no sigma given, no redundancy): the largest standard
  // uncertainty of a profile per unit of probe noise (dimensionless), i.e. how strongly the
  // layout amplifies noise. Absent when uncertainties were computed or not computable.
  std::optional<double> noise_gain;
  std::vector<double> offsets;   // the probe offsets used (mm)
  bool offsets_assumed = false;  // ProbeData::offsets_assumed
  double readings_span = 0;      // range of all probe readings (mm): a unit check
  double traverse = 0;           // x range (mm)

  // Human-readable multi-line summary (µm / µrad). A straightness the data do not resolve is
  // printed as "not resolved (U = … µm, 95 %)", not as a number; figures are rounded to the
  // resolution their uncertainty supports.
  std::string summary() const;
  // Plain-language warnings about what the result cannot support, one sentence each: a
  // straightness not resolved (its U reaches it: the layout cannot tell it from noise); no stated
  // uncertainty, with the reason and the layout's noise gain; probe offsets that were assumed,
  // not stated; readings that span less than 50 nm over a traverse of 5 mm or more (millimetres
  // read as micrometres?). Empty when the result is sound.
  std::vector<std::string> warnings() const;
};

// Separates workpiece, guide and (where modelled) pitch. Throws Error on invalid input or an
// unobservable layout (the message names the undetermined modes).
Result separate(const ProbeData& data, const Options& options = {});

// Expresses profiles in a reference exactly as separate() does for its results: if
// `parabola_free`, first the guide-quadratic gauge (w += c·t², g −= c·t², θ −= 2c·(x−x_c)/L² with
// c the t² coefficient of g's least-squares parabola, t = (x − x_c)/L on the guide's stations),
// then the LS (or min-zone) line of w and of g, and θ about its mean. Use it to put a known truth
// (a simulation, a reference measurement) in the same reference as a result. Reference::Seed is
// not accepted (it depends on the readings). Uncertainties are left untouched.
void express_in_reference(Profile& workpiece, Profile& guide, Profile* pitch, Reference reference,
                          bool parabola_free);

// What a probe layout can and cannot determine.
struct LayoutAnalysis {
  std::vector<long> steps;  // probe offsets in steps of h
  bool pitch_modelled = false;
  long extra_null_modes = 0;              // beyond those fixed by the reference/gauge
  std::vector<std::string> unobservable;  // all undetermined modes, named
  bool observable = true;                 // false: the solver refuses
  std::string message;                    // explanation when not observable
};

// Analyses the layout numerically (SVD of the design on a short stretch of stations).
LayoutAnalysis analyze_layout(const std::vector<long>& steps, bool angle_channel,
                              bool zero_difference_known, long stations);

}  // namespace trueaxis::separation
