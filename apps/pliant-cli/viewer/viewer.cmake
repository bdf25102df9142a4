# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# The interactive viewer behind `pliant view` (docs/viewer.md): GLFW for the window and input,
# Dear ImGui from Debian's libimgui-dev for the panels. Debian ships ImGui as libimgui.a plus
# headers, and its GLFW and OpenGL 3 backends only as sources under the package's documentation,
# so those two files are compiled into `pliant` here (never copied into the repository).
# Without GLFW, ImGui, the backend sources or the render module, the viewer is skipped and
# `pliant view` says what to install.
set(PLIANT_IMGUI_BACKENDS_DIR "/usr/share/doc/libimgui-dev/examples/backends"
    CACHE PATH "Folder holding Dear ImGui's imgui_impl_glfw.cpp and imgui_impl_opengl3.cpp")

find_package(glfw3 3.3 QUIET)
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
    pkg_check_modules(PLIANT_IMGUI QUIET IMPORTED_TARGET imgui)
endif()
find_path(PLIANT_IMGUI_BACKEND_INCLUDE imgui_impl_glfw.h PATH_SUFFIXES imgui/backends)

set(_pliant_viewer_missing "")
if(NOT glfw3_FOUND)
    list(APPEND _pliant_viewer_missing "GLFW 3.3 (libglfw3-dev)")
endif()
if(NOT PLIANT_IMGUI_FOUND)
    list(APPEND _pliant_viewer_missing "Dear ImGui (libimgui-dev, pkg-config imgui)")
endif()
if(NOT PLIANT_IMGUI_BACKEND_INCLUDE
   OR NOT EXISTS ${PLIANT_IMGUI_BACKENDS_DIR}/imgui_impl_glfw.cpp
   OR NOT EXISTS ${PLIANT_IMGUI_BACKENDS_DIR}/imgui_impl_opengl3.cpp)
    list(APPEND _pliant_viewer_missing "the ImGui GLFW/OpenGL3 backend sources (libimgui-dev)")
endif()
if(NOT TARGET pliant_render OR NOT TARGET pliant_session OR NOT TARGET pliant_remesh)
    list(APPEND _pliant_viewer_missing "the render, session and remesh modules")
endif()

if(_pliant_viewer_missing)
    message(STATUS "pliant view: skipped, missing ${_pliant_viewer_missing}")
    set(PLIANT_HAVE_VIEWER OFF CACHE INTERNAL "pliant view is built")
else()
    message(STATUS "pliant view: GLFW ${glfw3_VERSION}, Dear ImGui ${PLIANT_IMGUI_VERSION}")
    set(PLIANT_HAVE_VIEWER ON CACHE INTERNAL "pliant view is built")
    set(_pliant_imgui_backends
        ${PLIANT_IMGUI_BACKENDS_DIR}/imgui_impl_glfw.cpp
        ${PLIANT_IMGUI_BACKENDS_DIR}/imgui_impl_opengl3.cpp)
    # Third-party code: none of pliant's warnings (-Wconversion, -Werror) apply to it.
    set_source_files_properties(${_pliant_imgui_backends} PROPERTIES
        COMPILE_OPTIONS "-w"
        SKIP_LINTING ON
        SKIP_PRECOMPILE_HEADERS ON)
    # The embedded gl3w loader of Debian's ImGui 1.86 writes one entry past its table
    # (imgui_impl_opengl3_loader.h: 54 names into `ptr[53]`; UBSan reports it, fixed upstream
    # in 1.87). So the OpenGL 3 backend is built with IMGUI_IMPL_OPENGL_LOADER_CUSTOM instead:
    # the core-profile prototypes of Khronos' <GL/glcorearb.h>, resolved by GLVND's libOpenGL
    # (which dispatches to the GLX context GLFW makes current).
    find_package(OpenGL REQUIRED COMPONENTS OpenGL)
    set_property(SOURCE ${PLIANT_IMGUI_BACKENDS_DIR}/imgui_impl_opengl3.cpp APPEND PROPERTY
        COMPILE_OPTIONS -DIMGUI_IMPL_OPENGL_LOADER_CUSTOM -DGL_GLEXT_PROTOTYPES
                        -include GL/glcorearb.h)
    set(_pliant_viewer_sources
        ${CMAKE_CURRENT_LIST_DIR}/input_script.cpp
        ${CMAKE_CURRENT_LIST_DIR}/mesh_loader.cpp
        ${CMAKE_CURRENT_LIST_DIR}/picking.cpp
        ${CMAKE_CURRENT_LIST_DIR}/sim_scene.cpp
        ${CMAKE_CURRENT_LIST_DIR}/viewer.cpp
        ${CMAKE_CURRENT_LIST_DIR}/viewer_panels.cpp)
    # The viewer's files use no CLI11: loading the command's precompiled header only slows them.
    # Nor do they join the subcommands' unity batches (CMakeLists.txt next to this file).
    set_source_files_properties(${_pliant_viewer_sources} ${_pliant_imgui_backends} PROPERTIES
        SKIP_PRECOMPILE_HEADERS ON SKIP_UNITY_BUILD_INCLUSION ON)
    target_sources(pliant PRIVATE ${_pliant_viewer_sources} ${_pliant_imgui_backends})
    target_include_directories(pliant SYSTEM PRIVATE ${PLIANT_IMGUI_BACKEND_INCLUDE})
    target_compile_definitions(pliant PRIVATE PLIANT_HAVE_VIEWER=1)
    target_link_libraries(pliant PRIVATE glfw PkgConfig::PLIANT_IMGUI OpenGL::OpenGL
                                         Threads::Threads)
endif()
