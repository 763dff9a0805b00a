#pragma once
// Private: one factory per backend, chosen by create_context().

#include <memory>

#include "simreel/render/context.hpp"

namespace simreel::render::detail {

std::unique_ptr<Context> create_osmesa_context();
std::unique_ptr<Context> create_egl_context();

}  // namespace simreel::render::detail
