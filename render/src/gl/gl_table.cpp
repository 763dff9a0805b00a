#include "simreel/render/gl_table.hpp"

#include <stdexcept>
#include <string>

namespace simreel::render {

void GlTable::load(GetProcAddress get_proc_address) {
  if (get_proc_address == nullptr) throw std::runtime_error("no getProcAddress function given");
  // Converting void* to a function pointer is conditionally supported; POSIX dlsym relies on it.
#define SIMREEL_GL_LOAD(type, name)                                                       \
  name = reinterpret_cast<type>(get_proc_address("gl" #name));                            \
  if (name == nullptr) {                                                                  \
    throw std::runtime_error("OpenGL entry point gl" #name " is missing from the context"); \
  }
  SIMREEL_GL_FUNCTIONS(SIMREEL_GL_LOAD)
#undef SIMREEL_GL_LOAD
}

}  // namespace simreel::render
