// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// The OpenGL 3.3 core entry points the render module uses, as function pointers loaded at run
// time by `load_gl` (gl_loader.cpp) through the context's own GetProcAddress.
//
// Why our own table rather than libepoxy or glad: Debian has no glad package, and libepoxy finds
// its entry points through GLX or EGL only, so it cannot serve the OSMesa fallback, whose
// functions come from OSMesaGetProcAddress. A table of ~70 pointers filled from whichever
// GetProcAddress the context offers (eglGetProcAddress, OSMesaGetProcAddress,
// glfwGetProcAddress in the viewer) serves all three and needs no extra package; the prototypes
// come from Khronos' <GL/glcorearb.h> (Debian mesa-common-dev), which declares the core profile
// only, so a function outside GL 3.3 core cannot be called by mistake.
//
// The pointers are process-wide, like glad's. `load_gl` is called again whenever a different
// context is made current (EGL and OSMesa hand out different pointers).

#include <GL/glcorearb.h>

// X(type, name): every function in the table.
#define PLIANT_GL_FUNCTIONS(X)                                                   \
    X(PFNGLGETSTRINGPROC, glGetString)                                           \
    X(PFNGLGETINTEGERVPROC, glGetIntegerv)                                       \
    X(PFNGLGETERRORPROC, glGetError)                                             \
    X(PFNGLENABLEPROC, glEnable)                                                 \
    X(PFNGLDISABLEPROC, glDisable)                                               \
    X(PFNGLVIEWPORTPROC, glViewport)                                             \
    X(PFNGLCLEARCOLORPROC, glClearColor)                                         \
    X(PFNGLCLEARPROC, glClear)                                                   \
    X(PFNGLPOLYGONMODEPROC, glPolygonMode)                                       \
    X(PFNGLPOLYGONOFFSETPROC, glPolygonOffset)                                   \
    X(PFNGLDEPTHFUNCPROC, glDepthFunc)                                           \
    X(PFNGLDEPTHMASKPROC, glDepthMask)                                           \
    X(PFNGLPOINTSIZEPROC, glPointSize)                                           \
    X(PFNGLFINISHPROC, glFinish)                                                 \
    X(PFNGLPIXELSTOREIPROC, glPixelStorei)                                       \
    X(PFNGLREADPIXELSPROC, glReadPixels)                                         \
    X(PFNGLREADBUFFERPROC, glReadBuffer)                                         \
    X(PFNGLDRAWBUFFERPROC, glDrawBuffer)                                         \
    X(PFNGLGENTEXTURESPROC, glGenTextures)                                       \
    X(PFNGLDELETETEXTURESPROC, glDeleteTextures)                                 \
    X(PFNGLBINDTEXTUREPROC, glBindTexture)                                       \
    X(PFNGLTEXIMAGE2DPROC, glTexImage2D)                                         \
    X(PFNGLTEXSUBIMAGE2DPROC, glTexSubImage2D)                                   \
    X(PFNGLTEXPARAMETERIPROC, glTexParameteri)                                   \
    X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                                   \
    X(PFNGLGENBUFFERSPROC, glGenBuffers)                                         \
    X(PFNGLDELETEBUFFERSPROC, glDeleteBuffers)                                   \
    X(PFNGLBINDBUFFERPROC, glBindBuffer)                                         \
    X(PFNGLBUFFERDATAPROC, glBufferData)                                         \
    X(PFNGLBUFFERSUBDATAPROC, glBufferSubData)                                   \
    X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)                               \
    X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays)                         \
    X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)                               \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)               \
    X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)                       \
    X(PFNGLDRAWELEMENTSPROC, glDrawElements)                                     \
    X(PFNGLDRAWARRAYSPROC, glDrawArrays)                                         \
    X(PFNGLCREATESHADERPROC, glCreateShader)                                     \
    X(PFNGLSHADERSOURCEPROC, glShaderSource)                                     \
    X(PFNGLCOMPILESHADERPROC, glCompileShader)                                   \
    X(PFNGLGETSHADERIVPROC, glGetShaderiv)                                       \
    X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                             \
    X(PFNGLDELETESHADERPROC, glDeleteShader)                                     \
    X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                                   \
    X(PFNGLATTACHSHADERPROC, glAttachShader)                                     \
    X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                       \
    X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)                                     \
    X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)                           \
    X(PFNGLDELETEPROGRAMPROC, glDeleteProgram)                                   \
    X(PFNGLUSEPROGRAMPROC, glUseProgram)                                         \
    X(PFNGLBINDATTRIBLOCATIONPROC, glBindAttribLocation)                         \
    X(PFNGLBINDFRAGDATALOCATIONPROC, glBindFragDataLocation)                     \
    X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)                         \
    X(PFNGLUNIFORM1IPROC, glUniform1i)                                           \
    X(PFNGLUNIFORM1FPROC, glUniform1f)                                           \
    X(PFNGLUNIFORM3FPROC, glUniform3f)                                           \
    X(PFNGLUNIFORM3FVPROC, glUniform3fv)                                         \
    X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv)                             \
    X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                               \
    X(PFNGLDELETEFRAMEBUFFERSPROC, glDeleteFramebuffers)                         \
    X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                               \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, glFramebufferRenderbuffer)               \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, glFramebufferTexture2D)                     \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, glCheckFramebufferStatus)                 \
    X(PFNGLGENRENDERBUFFERSPROC, glGenRenderbuffers)                             \
    X(PFNGLDELETERENDERBUFFERSPROC, glDeleteRenderbuffers)                       \
    X(PFNGLBINDRENDERBUFFERPROC, glBindRenderbuffer)                             \
    X(PFNGLRENDERBUFFERSTORAGEPROC, glRenderbufferStorage)                       \
    X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, glRenderbufferStorageMultisample) \
    X(PFNGLBLITFRAMEBUFFERPROC, glBlitFramebuffer)

namespace pliant::render::gl
{

#define PLIANT_GL_DECLARE(type, name) extern type name;
PLIANT_GL_FUNCTIONS(PLIANT_GL_DECLARE)
#undef PLIANT_GL_DECLARE

/// True once a table has been loaded (any context).
bool is_loaded() noexcept;

}  // namespace pliant::render::gl
