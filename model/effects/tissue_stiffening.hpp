#pragma once
// Truth effect "tissue_stiffening" (EFFECTS.md 6): the colon wall stiffens with its indentation
// (exponential, Fung-type). Force-indentation law of the wall at a contact, b = 1 / f_ref:
//   f = f_ref (exp(delta / (c0 f_ref)) - 1)   <=>   delta(f) = c0 f_ref ln(1 + f / f_ref),
// tangent compliance d delta / d f = c0 / (1 + f / f_ref). The world solves for the total force
// with delta = c f, so the hook returns the secant compliance at the contact's force of the
// previous step: c(f) = delta(f) / f = c0 ln(1 + b f) / (b f) (c0 at f = 0 or b = 0).
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class TissueStiffening : public WorldEffect {
public:
    static constexpr const char* kName = "tissue_stiffening";
    struct Parameters {
        /// b = 1 / f_ref [1/N]; 0 = linear wall. Default 1/N (f_ref = 1 N): stated guess.
        double stiffening_per_N = 1.0;
        void validate(const effects::FieldName& field) const;
    };

    explicit TissueStiffening(const Parameters& p);
    /// Reads "stiffening_per_N" (b) or "reference_force_N" (f_ref = 1 / b), at most one of them.
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    double wall_compliance_mm_per_N(const ContactWallView& contact) const override;
    /// Secant compliance c0 ln(1 + b f) / (b f) at normal force f [mm/N].
    double secant_compliance_mm_per_N(double base_compliance_mm_per_N, double normal_force_N) const;
    /// Indentation delta(f) = c0 f_ref ln(1 + f / f_ref) [mm].
    double indentation_mm(double base_compliance_mm_per_N, double normal_force_N) const;

private:
    Parameters p_;
};

}  // namespace scopekin::model
