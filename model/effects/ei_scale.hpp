#pragma once
// Truth effect "ei_scale" (EFFECTS.md 4): the scope's bending stiffness scaled uniformly,
// EI_y, EI_z -> factor EI (e.g. the polymer sheath softened at body temperature).
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class EiScale : public WorldEffect {
public:
    static constexpr const char* kName = "ei_scale";
    struct Parameters {
        /// EI multiplier; 1 = unchanged. Default 0.85: ~15 % lower at body temperature (thesis 4.2.2).
        double factor = 0.85;
        void validate(const effects::FieldName& field) const;
    };

    explicit EiScale(const Parameters& p);
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    /// EI_y and EI_z times the factor; EA, GJ, shear stiffness and inertias unchanged (EFFECTS.md).
    void adjust_scope_sections(std::vector<BeamSection>& sections,
                               double scope_length_mm) const override;

private:
    Parameters p_;
};

}  // namespace scopekin::model
