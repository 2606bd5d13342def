#include "model/model_error.hpp"

#include <cmath>
#include <sstream>

namespace scopekin::model {
std::string number_text(double value) {
    std::ostringstream out;
    out << value;
    return out.str();
}

void require_finite(double value, const std::string& field) {
    if (!std::isfinite(value))
        throw ModelError(field + ": " + number_text(value) + " is not a finite number");
}

void require_positive(double value, const std::string& field) {
    require_finite(value, field);
    if (!(value > 0.0)) throw ModelError(field + ": " + number_text(value) + " must be > 0");
}

void require_non_negative(double value, const std::string& field) {
    require_finite(value, field);
    if (!(value >= 0.0)) throw ModelError(field + ": " + number_text(value) + " must be >= 0");
}

}  // namespace scopekin::model
