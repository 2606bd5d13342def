#pragma once
// The one error type of the reference model: a malformed or physically impossible input.
// The message always names the offending field (e.g. "element 3: length 0 mm must be > 0").
#include <stdexcept>
#include <string>

namespace scopekin::model {

class ModelError : public std::runtime_error {
public:
    explicit ModelError(const std::string& message) : std::runtime_error(message) {}
};

/// Throws ModelError("<field>: <value> must be <rule>") unless value is finite and > 0.
void require_positive(double value, const std::string& field);
/// Throws unless value is finite and >= 0.
void require_non_negative(double value, const std::string& field);
/// Throws unless value is finite.
void require_finite(double value, const std::string& field);
/// A number as it appears in error messages (shortest stream form, e.g. "0.25", "1e-06").
std::string number_text(double value);

}  // namespace scopekin::model
