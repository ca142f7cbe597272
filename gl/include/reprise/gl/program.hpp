#pragma once
// Shader plumbing on the current OpenGL ES context: compiling and linking with the driver's log
// in the error, float textures, and GL errors as a Status.
#include <GLES3/gl32.h>

#include "reprise/core/status.hpp"

namespace reprise::gl {

// `what` names the program in errors ("G-buffer", "reprojection").
Status link_program(const char* vertex, const char* fragment, const char* what, GLuint& program);
Status link_compute(const char* source, const char* what, GLuint& program);

// (Re)allocates `texture` as a w x h image of `format` (GL_RGBA32F, GL_R32F, GL_R32UI ...) with
// nearest filtering; leaves it bound to GL_TEXTURE_2D.
void allocate_texture(GLuint texture, GLenum format, int w, int h);

// Replaces `texture` (0: none yet) by a new immutable w x h texture of `format` with nearest
// filtering, as image load/store needs; leaves it bound to GL_TEXTURE_2D.
void immutable_texture(GLuint& texture, GLenum format, int w, int h);

// The pixel transfer format and type of a sized internal format this module allocates.
void transfer_format(GLenum internal_format, GLenum& format, GLenum& type);

// An error when the GL error flag is set (clears it): "OpenGL ES: <what>: error 0x0502".
Status check_errors(const char* what);

}  // namespace reprise::gl
