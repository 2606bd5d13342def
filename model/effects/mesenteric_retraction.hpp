#pragma once
// Truth effect "mesenteric_retraction" (EFFECTS.md 2): the stretched sigmoid mesentery pulls
// back on the scope that stretches it. On each inserted scope node whose closest point of the
// colon at rest is in the sigmoid:
//   excess = max(0, d - (R - r)),  d = distance of the node from the rest centerline,
//            R = lumen radius there, r = scope radius (the node pushes the wall out by `excess`),
//   F = -k_r l e_ref (excess / e_ref)^p u,  u = unit vector from the rest centerline to the node,
// with l the scope length the node carries. For p = 1 this is F = -k_r l excess u.
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class MesentericRetraction : public WorldEffect {
public:
    static constexpr const char* kName = "mesenteric_retraction";
    struct Parameters {
        double stiffness_N_per_mm2 = 0.002;  ///< k_r, N/mm of excess per mm of scope (stated guess)
        double exponent = 1.0;               ///< p >= 1; > 1 stiffens with the stretch
        double reference_excess_mm =
            10.0;  ///< e_ref: where the nonlinear law equals the linear one
        void validate(const effects::FieldName& field) const;
    };

    explicit MesentericRetraction(const Parameters& p);
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    void add_scope_loads(const WorldEffectView& view, std::vector<NodalLoad>& loads) const override;
    /// Force magnitude on a node carrying `node_length_mm` of scope pushed `excess_mm` beyond the rest wall [N].
    double force_N(double excess_mm, double node_length_mm) const;

private:
    Parameters p_;
};

}  // namespace scopekin::model
