#pragma once
// Truth effect "sigmoid_mobility" (EFFECTS.md 5): a slow, periodic disturbance of the mobile
// sigmoid (respiration, peristalsis) felt by the scope inside it: on each inserted scope node whose
// closest point of the colon at rest is in the sigmoid, a force per unit length
//   q(t) = A sin(2 pi f t + phi) d,  d a fixed unit direction (body frame),
// i.e. F = q(t) l on a node carrying l mm of scope. Deterministic: the phase is a parameter.
#include <memory>

#include "model/effects/effect_support.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

class SigmoidMobility : public WorldEffect {
public:
    static constexpr const char* kName = "sigmoid_mobility";
    struct Parameters {
        double amplitude_N_per_mm = 0.005;  ///< A (stated guess)
        double frequency_Hz = 0.25;         ///< f: respiration, 15 breaths per minute
        Eigen::Vector3d direction{0.0, 1.0,
                                  0.0};  ///< d, body frame; normalised (default colon: y cranial)
        double phase_rad = 0.0;          ///< phi
        void validate(const effects::FieldName& field) const;
    };

    explicit SigmoidMobility(const Parameters& p);
    static std::shared_ptr<const WorldEffect> read(const io::JsonObject& o);

    std::string name() const override { return kName; }
    nlohmann::json parameters() const override;
    void add_scope_loads(const WorldEffectView& view, std::vector<NodalLoad>& loads) const override;
    /// q(t) [N/mm], body frame.
    Eigen::Vector3d load_per_length_N_per_mm(double time_s) const;

private:
    Parameters p_;
};

}  // namespace scopekin::model
