#pragma once
// Truth effect "viscoadhesive_friction" (EFFECTS.md 1): the tissue's friction grows with the
// sliding speed, mu_eff = mu + min(c_v |v_slide|, max_friction_increase), on every contact.
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class ViscoadhesiveFriction : public WorldEffect {
public:
    static constexpr const char* kName = "viscoadhesive_friction";
    struct Parameters {
        double viscous_coefficient_s_per_mm =
            0.002;  ///< c_v: friction coefficient per mm/s of sliding (stated guess)
        double max_friction_increase = 0.25;  ///< cap on c_v |v_slide| (stated guess)
        void validate(const effects::FieldName& field) const;
    };

    explicit ViscoadhesiveFriction(const Parameters& p);
    /// Reads {"name": "viscoadhesive_friction", ...} strictly (keys as in Parameters).
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    using WorldEffect::friction_coefficient;
    double friction_coefficient(const ContactFrictionView& contact) const override;
    /// mu + min(c_v |v|, cap); exactly mu when c_v = 0.
    double effective_coefficient(double mu, double sliding_speed_mm_per_s) const;

private:
    Parameters p_;
};

}  // namespace scopekin::model
