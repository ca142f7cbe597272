#include "reprise/gl/context.hpp"

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl32.h>

namespace reprise::gl {

namespace {

bool has_extension(const char* list, const char* name) {
    if (!list) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)); p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

// The first EGL device backed by real hardware (not Mesa's software device).
EGLDisplay hardware_display() {
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!query_devices || !query_string || !get_display) return EGL_NO_DISPLAY;
    EGLint count = 0;
    if (!query_devices(0, nullptr, &count) || count <= 0) return EGL_NO_DISPLAY;
    std::vector<EGLDeviceEXT> devices(count);
    query_devices(count, devices.data(), &count);
    for (EGLDeviceEXT device : devices) {
        const char* extensions = query_string(device, EGL_EXTENSIONS);
        if (has_extension(extensions, "EGL_MESA_device_software")) continue;
        EGLDisplay display = get_display(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
        if (display != EGL_NO_DISPLAY) return display;
    }
    return EGL_NO_DISPLAY;
}

EGLDisplay surfaceless_display() {
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_display) return EGL_NO_DISPLAY;
    return get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
}

// EGL displays are per process and eglTerminate ends every context on one: a display is
// terminated only when the last Context on it goes (the renderer and gpu/ each hold one).
std::mutex display_users_mutex;
std::map<EGLDisplay, int> display_users;

void hold(EGLDisplay display) {
    std::lock_guard lock(display_users_mutex);
    ++display_users[display];
}

void release(EGLDisplay display) {
    std::lock_guard lock(display_users_mutex);
    if (--display_users[display] > 0) return;
    display_users.erase(display);
    eglTerminate(display);
}

}  // namespace

Status Context::create(std::unique_ptr<Context>& context) {
    const char* forced = std::getenv("REPRISE_EGL");
    std::string mode = forced ? forced : "";
    if (!mode.empty() && mode != "device" && mode != "surfaceless")
        return Status::error("REPRISE_EGL='" + mode + "': expected device or surfaceless");
    const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    EGLDisplay display = EGL_NO_DISPLAY;
    // libglvnd offers enumeration as part of EGL_EXT_device_base (NVIDIA's driver behind it).
    if (mode != "surfaceless" && (has_extension(client_extensions, "EGL_EXT_device_enumeration") ||
                                  has_extension(client_extensions, "EGL_EXT_device_base")))
        display = hardware_display();
    if (display == EGL_NO_DISPLAY && mode == "device")
        return Status::error("EGL: no hardware EGL device found (REPRISE_EGL=device)");
    if (display == EGL_NO_DISPLAY) {
        if (!has_extension(client_extensions, "EGL_MESA_platform_surfaceless"))
            return Status::error(
                "EGL: Mesa's surfaceless platform is not available "
                "(install libegl-mesa0 and libgl1-mesa-dri)");
        display = surfaceless_display();
    }
    EGLint major = 0, minor = 0;
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor))
        return Status::error("EGL: cannot initialise a display (error 0x" +
                             std::to_string(eglGetError()) + ")");
    hold(display);
    if (!eglBindAPI(EGL_OPENGL_ES_API)) {
        release(display);
        return Status::error("EGL: OpenGL ES is not supported");
    }
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE,
                                        EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configs = 0;
    if (!eglChooseConfig(display, config_attributes, &config, 1, &configs) || configs < 1) {
        release(display);
        return Status::error("EGL: no OpenGL ES 3 configuration");
    }
    EGLContext egl_context = EGL_NO_CONTEXT;
    for (EGLint minor_version : {2, 1, 0}) {
        const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION,
                                     minor_version, EGL_NONE};
        egl_context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
        if (egl_context != EGL_NO_CONTEXT) break;
    }
    if (egl_context == EGL_NO_CONTEXT) {
        release(display);
        return Status::error("EGL: cannot create an OpenGL ES 3 context");
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_context)) {
        eglDestroyContext(display, egl_context);
        release(display);
        return Status::error("EGL: cannot make the context current without a surface");
    }
    context.reset(new Context());
    context->display_ = display;
    context->context_ = egl_context;
    const Status usable = context->describe(false);
    if (!usable.ok()) context.reset();
    return usable;
}

Status Context::adopt_current(std::unique_ptr<Context>& context) {
    EGLContext current = eglGetCurrentContext();
    if (current == EGL_NO_CONTEXT)
        return Status::error("gl: no EGL context is current on this thread to adopt");
    if (eglQueryAPI() != EGL_OPENGL_ES_API)
        return Status::error("gl: the current EGL context is not an OpenGL ES one");
    std::unique_ptr<Context> made(new Context());
    made->display_ = eglGetCurrentDisplay();
    made->context_ = current;
    made->adopted_ = true;
    REPRISE_TRY(made->describe(true));
    context = std::move(made);
    return {};
}

Status Context::describe(bool compute) {
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    description_ = std::string(renderer ? renderer : "?") + ", " + (version ? version : "?");
    const char* gl_extensions = reinterpret_cast<const char*>(glGetString(GL_EXTENSIONS));
    GLint gl_major = 0, gl_minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &gl_major);
    glGetIntegerv(GL_MINOR_VERSION, &gl_minor);
    if (compute && !(gl_major > 3 || (gl_major == 3 && gl_minor >= 1)))
        return Status::error("OpenGL ES " + std::to_string(gl_major) + "." +
                             std::to_string(gl_minor) + ": compute shaders need OpenGL ES 3.1 (" +
                             description_ + ")");
    const bool float_targets = gl_major > 3 || (gl_major == 3 && gl_minor >= 2) ||
                               has_extension(gl_extensions, "GL_EXT_color_buffer_float");
    if (!float_targets)
        return Status::error(
            "OpenGL ES: float render targets (GL_EXT_color_buffer_float) are "
            "not supported");
    return {};
}

Context::~Context() {
    if (!display_ || adopted_) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display_, context_);
    release(static_cast<EGLDisplay>(display_));
}

void Context::make_current() const {
    if (!adopted_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_);
}

Status Context::acquire() const {
    if (adopted_) {
        if (eglGetCurrentContext() == context_) return {};
        return Status::error(
            "gl: the adopted OpenGL ES context is not current on this thread; make it current "
            "before each call");
    }
    if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_TRUE) return {};
    return Status::error("gl: the context cannot be made current on this thread (EGL error " +
                         std::to_string(eglGetError()) +
                         "): another thread holds it; use it from one thread at a time");
}

}  // namespace reprise::gl
