#include "sim/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/osmesa.h>
#include <dlfcn.h>

#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"

namespace segslam::sim {
namespace {

constexpr unsigned int kGlRenderer = 0x1F01;  // GL_RENDERER
using GetStringFn = const unsigned char* (*)(unsigned int);

std::string EglErrorName(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "EGL error 0x%04x", static_cast<unsigned>(code));
      return buf;
    }
  }
}

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// The platform libraries are opened with dlopen(RTLD_LOCAL) rather than linked, so
// that their *GetProcAddress symbols stay out of the global namespace. MuJoCo 2.2.2
// loads its GL entry points once per process, at the first mjr_makeContext: it takes
// eglGetProcAddress from the global namespace before OSMesaGetProcAddress, and
// otherwise the first platform library found among the loaded ones. Linking both
// made it always take EGL's (glvnd) entry points, which do nothing under an OSMesa
// context ("gladLoadGL error"). Opened locally, the first back-end used would pick the
// loader for the whole process, and EGL first then OSMesa failed the same way.
// What works: on Mesa, OSMesa's entry points (Mesa's shared libglapi dispatch) also
// drive a Mesa EGL context. So whenever the GL implementation is Mesa, libOSMesa is
// promoted to RTLD_GLOBAL before MuJoCo loads GL, and MuJoCo takes
// OSMesaGetProcAddress for both back-ends, in any order. A non-Mesa EGL (a GPU
// vendor's) leaves the choice to MuJoCo, which then finds libEGL; mixing it with
// OSMesa in one process is refused with an Error (see ClaimLoader).
struct OsmesaApi {
  void* lib = nullptr;
  decltype(&OSMesaCreateContextExt) create_context_ext = nullptr;
  decltype(&OSMesaMakeCurrent) make_current = nullptr;
  decltype(&OSMesaDestroyContext) destroy_context = nullptr;
  decltype(&OSMesaGetProcAddress) get_proc_address = nullptr;
};

struct EglApi {
  void* lib = nullptr;
  decltype(&eglGetProcAddress) get_proc_address = nullptr;
  decltype(&eglQueryString) query_string = nullptr;
  decltype(&eglGetError) get_error = nullptr;
  decltype(&eglInitialize) initialize = nullptr;
  decltype(&eglTerminate) terminate = nullptr;
  decltype(&eglChooseConfig) choose_config = nullptr;
  decltype(&eglBindAPI) bind_api = nullptr;
  decltype(&eglCreateContext) create_context = nullptr;
  decltype(&eglDestroyContext) destroy_context = nullptr;
  decltype(&eglMakeCurrent) make_current = nullptr;
};

void* OpenLibrary(const std::vector<const char*>& names, std::string* tried) {
  for (const char* name : names) {
    if (void* lib = dlopen(name, RTLD_NOW | RTLD_LOCAL)) return lib;
    if (!tried->empty()) *tried += ", ";
    *tried += name;
  }
  return nullptr;
}

template <typename Fn>
void Resolve(void* lib, const char* name, const char* lib_name, Fn* fn) {
  *fn = reinterpret_cast<Fn>(dlsym(lib, name));
  if (*fn == nullptr) throw Error(std::string(lib_name) + ": symbol " + name + " missing");
}

const OsmesaApi& Osmesa() {
  static std::mutex mutex;
  static OsmesaApi api;
  std::lock_guard<std::mutex> lock(mutex);
  if (api.lib == nullptr) {
    std::string tried;
    void* lib = OpenLibrary({"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"}, &tried);
    if (lib == nullptr) throw Error("OSMesa: cannot load " + tried);
    OsmesaApi loaded;
    loaded.lib = lib;
    Resolve(lib, "OSMesaCreateContextExt", "OSMesa", &loaded.create_context_ext);
    Resolve(lib, "OSMesaMakeCurrent", "OSMesa", &loaded.make_current);
    Resolve(lib, "OSMesaDestroyContext", "OSMesa", &loaded.destroy_context);
    Resolve(lib, "OSMesaGetProcAddress", "OSMesa", &loaded.get_proc_address);
    api = loaded;
  }
  return api;
}

const EglApi& Egl() {
  static std::mutex mutex;
  static EglApi api;
  std::lock_guard<std::mutex> lock(mutex);
  if (api.lib == nullptr) {
    std::string tried;
    void* lib = OpenLibrary({"libEGL.so.1", "libEGL.so"}, &tried);
    if (lib == nullptr) throw Error("EGL: cannot load " + tried);
    EglApi loaded;
    loaded.lib = lib;
    Resolve(lib, "eglGetProcAddress", "EGL", &loaded.get_proc_address);
    Resolve(lib, "eglQueryString", "EGL", &loaded.query_string);
    Resolve(lib, "eglGetError", "EGL", &loaded.get_error);
    Resolve(lib, "eglInitialize", "EGL", &loaded.initialize);
    Resolve(lib, "eglTerminate", "EGL", &loaded.terminate);
    Resolve(lib, "eglChooseConfig", "EGL", &loaded.choose_config);
    Resolve(lib, "eglBindAPI", "EGL", &loaded.bind_api);
    Resolve(lib, "eglCreateContext", "EGL", &loaded.create_context);
    Resolve(lib, "eglDestroyContext", "EGL", &loaded.destroy_context);
    Resolve(lib, "eglMakeCurrent", "EGL", &loaded.make_current);
    api = loaded;
  }
  return api;
}

// Which GetProcAddress MuJoCo's process-wide GL loader is (or will be) bound to.
enum class Loader { kUnset, kMesaGlapi, kVendorEgl };

// Records the loader the new context needs; throws when the process already committed
// MuJoCo to the other one.
void ClaimLoader(Loader needed, const std::string& who) {
  static std::mutex mutex;
  static Loader claimed = Loader::kUnset;
  std::lock_guard<std::mutex> lock(mutex);
  if (claimed == Loader::kUnset) {
    if (needed == Loader::kMesaGlapi) {
      // Promote libOSMesa to the global namespace, where MuJoCo looks first
      // (libEGL stays local, so eglGetProcAddress is not found there).
      Osmesa();
      if (dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD) == nullptr &&
          dlopen("libOSMesa.so.6", RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD) == nullptr &&
          dlopen("libOSMesa.so", RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD) == nullptr) {
        throw Error(who + ": cannot make libOSMesa global for MuJoCo's GL loader");
      }
    }
    claimed = needed;
    return;
  }
  if (claimed != needed) {
    throw Error(who + ": cannot mix OSMesa with a non-Mesa EGL in one process (MuJoCo "
                      "loads GL once per process); use one GL back-end per process");
  }
}

}  // namespace

GlBackend ParseGlBackend(const std::string& name) {
  if (name == "osmesa") return GlBackend::kOsmesa;
  if (name == "egl") return GlBackend::kEgl;
  throw Error("unknown GL back-end '" + name + "' (expected osmesa or egl)");
}

std::string GlBackendName(GlBackend backend) {
  return backend == GlBackend::kOsmesa ? "osmesa" : "egl";
}

struct GlContext::Impl {
  GlBackend backend = GlBackend::kOsmesa;
  int width = 0;
  int height = 0;
  // OSMesa: the context and the colour buffer it is bound to (MuJoCo draws into its
  // own off-screen framebuffer object; this buffer only has to exist).
  OSMesaContext osmesa = nullptr;
  std::vector<unsigned char> osmesa_buffer;
  // EGL: display and context; no surface (EGL_KHR_surfaceless_context).
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string renderer;

  void InitOsmesa();
  void InitEgl();
  bool TryEglDisplay(EGLDisplay candidate, std::string* why);
  void MakeCurrent();
};

void GlContext::Impl::InitOsmesa() {
  // RGBA colour, 24-bit depth, 8-bit stencil, no accumulation buffer.
  osmesa = Osmesa().create_context_ext(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (osmesa == nullptr) throw Error("OSMesa: OSMesaCreateContextExt failed");
  osmesa_buffer.assign(static_cast<size_t>(width) * height * 4, 0);
  MakeCurrent();
}

// Initialises `candidate`, creates a desktop-GL context on it and makes it current
// without a surface. On failure terminates the display and says why.
bool GlContext::Impl::TryEglDisplay(EGLDisplay candidate, std::string* why) {
  if (candidate == EGL_NO_DISPLAY) {
    *why = "no display (" + EglErrorName(Egl().get_error()) + ")";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (Egl().initialize(candidate, &major, &minor) != EGL_TRUE) {
    *why = "eglInitialize failed (" + EglErrorName(Egl().get_error()) + ")";
    return false;
  }
  const EGLint config_attribs[] = {EGL_RED_SIZE, 8, EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8,
                                   EGL_ALPHA_SIZE, 8, EGL_DEPTH_SIZE, 24, EGL_STENCIL_SIZE, 8,
                                   EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint num_configs = 0;
  if (Egl().choose_config(candidate, config_attribs, &config, 1, &num_configs) != EGL_TRUE ||
      num_configs < 1) {
    // Surfaceless displays may offer configs without surfaces only: accept any.
    const EGLint any_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    if (Egl().choose_config(candidate, any_attribs, &config, 1, &num_configs) != EGL_TRUE ||
        num_configs < 1) {
      config = nullptr;  // EGL_KHR_no_config_context
    }
  }
  if (Egl().bind_api(EGL_OPENGL_API) != EGL_TRUE) {
    *why = "Egl().bind_api(EGL_OPENGL_API) failed (" + EglErrorName(Egl().get_error()) + ")";
    Egl().terminate(candidate);
    return false;
  }
  EGLContext ctx = Egl().create_context(candidate, config, EGL_NO_CONTEXT, nullptr);
  if (ctx == EGL_NO_CONTEXT) {
    *why = "eglCreateContext failed (" + EglErrorName(Egl().get_error()) + ")";
    Egl().terminate(candidate);
    return false;
  }
  if (Egl().make_current(candidate, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx) != EGL_TRUE) {
    *why = "eglMakeCurrent without surface failed (" + EglErrorName(Egl().get_error()) + ")";
    Egl().destroy_context(candidate, ctx);
    Egl().terminate(candidate);
    return false;
  }
  display = candidate;
  context = ctx;
  return true;
}

void GlContext::Impl::InitEgl() {
  const char* client_ext = Egl().query_string(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client_ext == nullptr) {
    throw Error("EGL: no client extensions (" + EglErrorName(Egl().get_error()) +
                "); is an EGL vendor library installed?");
  }
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      Egl().get_proc_address("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr) {
    throw Error("EGL: eglGetPlatformDisplayEXT is not available");
  }
  std::string why;
  // 1. A hardware device (a GPU), when EGL_EXT_platform_device enumerates one. Mesa's
  //    software device (EGL_MESA_device_software) is skipped: surfaceless is the
  //    path checked on CPU-only machines.
  if (HasExtension(client_ext, "EGL_EXT_platform_device")) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
        Egl().get_proc_address("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        Egl().get_proc_address("eglQueryDeviceStringEXT"));
    EGLint count = 0;
    if (query_devices != nullptr && query_devices(0, nullptr, &count) == EGL_TRUE &&
        count > 0) {
      std::vector<EGLDeviceEXT> devices(count);
      query_devices(count, devices.data(), &count);
      for (EGLint i = 0; i < count; ++i) {
        const char* dev_ext = query_device_string != nullptr
                                  ? query_device_string(devices[i], EGL_EXTENSIONS)
                                  : nullptr;
        if (HasExtension(dev_ext, "EGL_MESA_device_software")) continue;
        EGLDisplay candidate =
            get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (TryEglDisplay(candidate, &why)) return;
      }
    }
  }
  // 2. Mesa's surfaceless platform (llvmpipe without a GPU).
  if (!HasExtension(client_ext, "EGL_MESA_platform_surfaceless")) {
    throw Error("EGL: no usable device and no EGL_MESA_platform_surfaceless" +
                (why.empty() ? std::string() : " (device: " + why + ")"));
  }
  EGLDisplay candidate = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA,
                                              EGL_DEFAULT_DISPLAY, nullptr);
  if (!TryEglDisplay(candidate, &why)) {
    throw Error("EGL: cannot initialise the surfaceless display: " + why);
  }
}

void GlContext::Impl::MakeCurrent() {
  if (backend == GlBackend::kOsmesa) {
    if (Osmesa().make_current(osmesa, osmesa_buffer.data(), 0x1401 /* GL_UNSIGNED_BYTE */,
                          width, height) == 0) {
      throw Error("OSMesa: OSMesaMakeCurrent failed");
    }
  } else {
    if (Egl().make_current(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
      throw Error("EGL: eglMakeCurrent failed (" + EglErrorName(Egl().get_error()) + ")");
    }
  }
}

GlContext::GlContext(GlBackend backend, int max_width, int max_height)
    : impl_(std::make_unique<Impl>()) {
  if (max_width <= 0 || max_height <= 0) {
    throw Error("GL context: invalid size " + std::to_string(max_width) + "x" +
                std::to_string(max_height));
  }
  impl_->backend = backend;
  impl_->width = max_width;
  impl_->height = max_height;
  GetStringFn get_string = nullptr;
  if (backend == GlBackend::kOsmesa) {
    impl_->InitOsmesa();
    ClaimLoader(Loader::kMesaGlapi, "OSMesa");
    get_string = reinterpret_cast<GetStringFn>(Osmesa().get_proc_address("glGetString"));
  } else {
    impl_->InitEgl();
    const char* vendor = Egl().query_string(impl_->display, EGL_VENDOR);
    const bool mesa = vendor != nullptr && std::strstr(vendor, "Mesa") != nullptr;
    // On Mesa, EGL works with OSMesa's entry points; without libOSMesa, fall back to
    // EGL's own (then OSMesa cannot join later).
    bool have_osmesa = true;
    try {
      Osmesa();
    } catch (const Error&) {
      have_osmesa = false;
    }
    ClaimLoader(mesa && have_osmesa ? Loader::kMesaGlapi : Loader::kVendorEgl, "EGL");
    get_string = reinterpret_cast<GetStringFn>(Egl().get_proc_address("glGetString"));
  }
  const unsigned char* name = get_string != nullptr ? get_string(kGlRenderer) : nullptr;
  impl_->renderer = name != nullptr ? reinterpret_cast<const char*>(name) : "unknown";
}

GlContext::~GlContext() {
  if (impl_->backend == GlBackend::kOsmesa) {
    if (impl_->osmesa != nullptr) Osmesa().destroy_context(impl_->osmesa);
  } else if (impl_->display != EGL_NO_DISPLAY) {
    Egl().make_current(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (impl_->context != EGL_NO_CONTEXT) Egl().destroy_context(impl_->display, impl_->context);
    // The display is not terminated: EGL displays are per-process singletons and
    // another GlContext may still use the same one.
  }
}

void GlContext::MakeCurrent() { impl_->MakeCurrent(); }
std::string GlContext::renderer() const { return impl_->renderer; }
GlBackend GlContext::backend() const { return impl_->backend; }

}  // namespace segslam::sim
