// Opens libtrueaxis_occt.so on first use (see occt_api.hpp).
#include <dlfcn.h>
#include <fmt/format.h>

#include "occt_api.hpp"
#include "trueaxis/error.hpp"

namespace trueaxis::design::detail {

const OcctApi& load_occt_api(const std::string& library) {
  // dlerror() is per thread; clear anything an earlier call left.
  dlerror();
  void* handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    const char* why = dlerror();
    throw Error(fmt::format(
        "cannot load {}, the part of trueaxis that reads STEP files and evaluates NURBS curves "
        "and scanning paths (with Open CASCADE Technology): {}; is trueaxis installed completely?",
        library, why ? why : "unknown reason"));
  }
  auto* entry = reinterpret_cast<OcctEntry*>(dlsym(handle, kOcctEntry));
  const OcctApi* api = entry ? entry() : nullptr;
  if (!api || !api->tag || occt_api_tag() != api->tag) {
    dlclose(handle);
    throw Error(fmt::format(
        "{} is from another build of trueaxis (its interface '{}', this program's '{}'): "
        "install trueaxis again",
        library, api && api->tag ? api->tag : "none", occt_api_tag()));
  }
  return *api;  // the library stays loaded for the life of the process
}

const OcctApi& occt_api() {
  // Initialised once, thread-safely; if loading throws, the next call tries again.
  static const OcctApi& api = load_occt_api(kOcctLibrary);
  return api;
}

}  // namespace trueaxis::design::detail
