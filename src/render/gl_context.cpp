#include "pmg/render/gl_context.hpp"

#include <cstdio>
#include <cstdlib>
#include <string>

#include <GLFW/glfw3.h>

namespace pmg::render {

namespace {

std::string g_last_glfw_error;  // set by the GLFW error callback (set-up code, one thread)

void onGlfwError(int code, const char* description) {
  char buf[512];
  std::snprintf(buf, sizeof(buf), "%s (GLFW error 0x%x)", description ? description : "unknown error", code);
  g_last_glfw_error = buf;
}

const char* kXvfbHint =
    "run under a virtual X server: scripts/render_sil.sh starts Xvfb when $DISPLAY is unset, or "
    "`xvfb-run -a -s \"-screen 0 1280x1024x24\" pmg_render_log ...` (Debian packages xvfb, "
    "libgl1-mesa-dri; see docs/render.md)";

using GetStringFn = const GLubyte* (*)(GLenum);

}  // namespace

std::unique_ptr<GlContext> GlContext::create() {
  const char* display = std::getenv("DISPLAY");
  if (display == nullptr || display[0] == '\0')
    throw RenderError(std::string("cannot create an OpenGL context: no X display ($DISPLAY is not set); ") +
                      kXvfbHint);
  glfwSetErrorCallback(onGlfwError);
  g_last_glfw_error.clear();
  if (glfwInit() != GLFW_TRUE)
    throw RenderError("cannot create an OpenGL context: GLFW cannot initialise on DISPLAY=" + std::string(display) +
                      " (" + g_last_glfw_error + "); is an X server running there? " + kXvfbHint);
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_FALSE);
  GLFWwindow* window = glfwCreateWindow(1, 1, "pmg_render", nullptr, nullptr);
  if (window == nullptr) {
    const std::string why = g_last_glfw_error;
    glfwTerminate();
    throw RenderError("cannot create an OpenGL context on DISPLAY=" + std::string(display) + ": " + why +
                      "; the X server needs the GLX extension and an OpenGL driver (Mesa: Debian "
                      "package libgl1-mesa-dri; Xvfb provides GLX by default)");
  }
  glfwMakeContextCurrent(window);
  std::unique_ptr<GlContext> context(new GlContext());
  context->window_ = window;

  auto get_string = reinterpret_cast<GetStringFn>(glfwGetProcAddress("glGetString"));
  auto text = [&](GLenum name) {
    const GLubyte* s = get_string ? get_string(name) : nullptr;
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  context->vendor_ = text(GL_VENDOR);
  context->renderer_ = text(GL_RENDERER);
  context->version_ = text(GL_VERSION);

  // mjr_makeContext needs OpenGL >= 1.5 with framebuffer objects (core since 3.0).
  const int major = glfwGetWindowAttrib(window, GLFW_CONTEXT_VERSION_MAJOR);
  const int minor = glfwGetWindowAttrib(window, GLFW_CONTEXT_VERSION_MINOR);
  const bool version_ok = major > 1 || (major == 1 && minor >= 5);
  const bool fbo_ok = major >= 3 || glfwExtensionSupported("GL_ARB_framebuffer_object") == GLFW_TRUE;
  if (!version_ok || !fbo_ok)
    throw RenderError("the OpenGL context on DISPLAY=" + std::string(display) + " (" + context->renderer_ +
                      ", GL " + context->version_ +
                      ") cannot host MuJoCo's renderer: it needs OpenGL >= 1.5 with "
                      "GL_ARB_framebuffer_object (Mesa llvmpipe from libgl1-mesa-dri has both)");
  return context;
}

bool GlContext::isCurrent() { return glfwGetCurrentContext() != nullptr; }

GlContext::~GlContext() {
  if (window_ != nullptr) {
    glfwMakeContextCurrent(nullptr);
    glfwDestroyWindow(static_cast<GLFWwindow*>(window_));
  }
  glfwTerminate();
}

}  // namespace pmg::render
