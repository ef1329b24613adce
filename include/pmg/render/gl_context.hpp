#pragma once
/// @file gl_context.hpp
/// The OpenGL context MuJoCo 2.2's renderer needs (mjr_makeContext reads GL function pointers
/// from the context that is current on the calling thread). Made from a hidden GLFW window on the
/// X display named by $DISPLAY; on a machine without a GPU or screen that display is Xvfb and the
/// GL implementation Mesa's llvmpipe (software), see docs/render.md.
/// Setup code: allocates and throws. One GlContext per process at a time (GLFW is global state).

#include <memory>
#include <stdexcept>
#include <string>

namespace pmg::render {

/// Every failure of the rendering set-up (no display, no GL context, MuJoCo renderer errors).
/// what() names what is missing and how to get it.
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A current OpenGL context owned by a hidden 1×1 GLFW window (rendering goes to MuJoCo's
/// offscreen framebuffer, so the window size does not limit the image size).
class GlContext {
 public:
  /// Initialises GLFW, creates the hidden window and makes its context current on this thread.
  /// Checks what mjr_makeContext needs: OpenGL ≥ 1.5 with GL_ARB_framebuffer_object (core in 3.0).
  /// @throws RenderError naming what is missing, e.g. "no X display ($DISPLAY is not set): run
  ///   under Xvfb (scripts/render_sil.sh starts one)" or GLFW's own message.
  static std::unique_ptr<GlContext> create();

  /// Whether a GlContext's OpenGL context is current on the calling thread.
  static bool isCurrent();

  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  const std::string& vendor() const { return vendor_; }      ///< GL_VENDOR, e.g. "Mesa"
  const std::string& renderer() const { return renderer_; }  ///< GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& version() const { return version_; }    ///< GL_VERSION string

 private:
  GlContext() = default;
  void* window_ = nullptr;  // GLFWwindow*, kept opaque so users need no GLFW headers
  std::string vendor_, renderer_, version_;
};

}  // namespace pmg::render
