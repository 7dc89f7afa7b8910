// Off-screen OpenGL contexts for MuJoCo rendering without a display: Mesa's OSMesa
// (always software) or EGL (a GPU where the EGL device platform offers one, else
// Mesa's surfaceless platform, llvmpipe on a CPU-only machine).
//
// MuJoCo 2.2.2 resolves its GL entry points once per process, at the first
// mjr_makeContext, through whichever *GetProcAddress it finds first (eglGetProcAddress
// before OSMesaGetProcAddress). GlContext makes that choice work for both back-ends in
// one process; see gl_context.cpp for what was found on Mesa 22.3.
#pragma once

#include <memory>
#include <string>

namespace segslam::sim {

enum class GlBackend { kOsmesa, kEgl };

// "osmesa" or "egl"; anything else throws segslam::Error
// "unknown GL back-end 'x' (expected osmesa or egl)".
GlBackend ParseGlBackend(const std::string& name);
// "osmesa" or "egl".
std::string GlBackendName(GlBackend backend);

// Owns an off-screen GL context, made current on the constructing thread by the
// constructor. Rendering into it must happen on a thread where it is current (call
// MakeCurrent() after switching threads). Not copyable, not movable.
class GlContext {
 public:
  // Creates the context with room for frames up to max_width x max_height pixels.
  // Throws segslam::Error with a one-line reason when the back-end is unavailable
  // (e.g. the EGL display cannot be initialised) or the context cannot be created.
  GlContext(GlBackend backend, int max_width, int max_height);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // Makes this context current on the calling thread; throws segslam::Error on failure.
  void MakeCurrent();
  // GL_RENDERER of the context, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string renderer() const;
  GlBackend backend() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace segslam::sim
