#pragma once
// Truth effect "ei_profile" (EFFECTS.md 3): the scope's bending stiffness varies along it. A
// factor linear in the distance s from the tip, f(s) = f_tip + (f_handle - f_tip) s / L, times
// an optional soft distal bending section (factor f_bend for s < bending_section_length_mm).
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class EiProfile : public WorldEffect {
public:
    static constexpr const char* kName = "ei_profile";
    struct Parameters {
        double tip_factor = 0.75;  ///< EI multiplier at the tip (distal part softer, thesis 4.2.2)
        double handle_factor = 1.25;  ///< EI multiplier at the handle end
        double bending_section_length_mm =
            0.0;                              ///< soft distal section; 0 = none (CF-Q160L: ~100 mm)
        double bending_section_factor = 1.0;  ///< extra EI multiplier inside it
        void validate(const effects::FieldName& field) const;
    };

    explicit EiProfile(const Parameters& p);
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    /// Each element's EI_y, EI_z times the factor at its midpoint; EA, GJ, shear stiffness and
    /// inertias unchanged (EFFECTS.md).
    void adjust_scope_sections(std::vector<BeamSection>& sections,
                               double scope_length_mm) const override;
    /// The EI multiplier at `arc_from_tip_mm` on a scope of `scope_length_mm`.
    double factor_at(double arc_from_tip_mm, double scope_length_mm) const;

private:
    Parameters p_;
};

}  // namespace scopekin::model
