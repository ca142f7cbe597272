#include "reprise/gl/program.hpp"

#include <cstdio>
#include <string>

namespace reprise::gl {

namespace {

Status compile(GLenum type, const char* source, const char* what, GLuint& shader) {
    shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok) return {};
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    return Status::error(std::string("OpenGL ES: the ") + what +
                         " shader does not compile: " + log);
}

Status link(const GLuint* shaders, int count, const char* what, GLuint& program) {
    program = glCreateProgram();
    for (int i = 0; i < count; ++i) glAttachShader(program, shaders[i]);
    glLinkProgram(program);
    GLint linked = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &linked);
    if (linked) return {};
    char log[2048] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    return Status::error(std::string("OpenGL ES: the ") + what + " program does not link: " + log);
}

}  // namespace

Status link_program(const char* vertex, const char* fragment, const char* what, GLuint& program) {
    GLuint shaders[2] = {};
    Status status = compile(GL_VERTEX_SHADER, vertex, what, shaders[0]);
    if (status.ok()) status = compile(GL_FRAGMENT_SHADER, fragment, what, shaders[1]);
    if (status.ok()) status = link(shaders, 2, what, program);
    glDeleteShader(shaders[0]);
    glDeleteShader(shaders[1]);
    return status;
}

Status link_compute(const char* source, const char* what, GLuint& program) {
    GLuint shader = 0;
    Status status = compile(GL_COMPUTE_SHADER, source, what, shader);
    if (status.ok()) status = link(&shader, 1, what, program);
    glDeleteShader(shader);
    return status;
}

void transfer_format(GLenum internal_format, GLenum& format, GLenum& type) {
    switch (internal_format) {
        case GL_RGBA32F:
            format = GL_RGBA, type = GL_FLOAT;
            return;
        case GL_RGB32F:
            format = GL_RGB, type = GL_FLOAT;
            return;
        case GL_RG32F:
            format = GL_RG, type = GL_FLOAT;
            return;
        case GL_R32F:
            format = GL_RED, type = GL_FLOAT;
            return;
        case GL_R32UI:
            format = GL_RED_INTEGER, type = GL_UNSIGNED_INT;
            return;
        case GL_R8UI:
            format = GL_RED_INTEGER, type = GL_UNSIGNED_BYTE;
            return;
        default:
            format = GL_RGBA, type = GL_FLOAT;
            return;
    }
}

void allocate_texture(GLuint texture, GLenum format, int w, int h) {
    GLenum pixel_format = 0, type = 0;
    transfer_format(format, pixel_format, type);
    glBindTexture(GL_TEXTURE_2D, texture);
    glTexImage2D(GL_TEXTURE_2D, 0, GLint(format), w, h, 0, pixel_format, type, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

void immutable_texture(GLuint& texture, GLenum format, int w, int h) {
    if (texture) glDeleteTextures(1, &texture);
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glTexStorage2D(GL_TEXTURE_2D, 1, format, w, h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
}

Status check_errors(const char* what) {
    const GLenum error = glGetError();
    if (error == GL_NO_ERROR) return {};
    while (glGetError() != GL_NO_ERROR) {
    }
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", unsigned(error));
    return Status::error(std::string("OpenGL ES: ") + what + ": error " + code);
}

}  // namespace reprise::gl
