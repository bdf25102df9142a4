// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#include "render/program.h"

#include <array>
#include <string>
#include <vector>

namespace pliant::render
{
namespace
{

core::Result<GLuint> compile(GLenum stage, const char* source, const char* name)
{
    const GLuint shader = gl::glCreateShader(stage);
    gl::glShaderSource(shader, 1, &source, nullptr);
    gl::glCompileShader(shader);
    GLint ok = 0;
    gl::glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok == GL_TRUE)
        return shader;
    GLint length = 0;
    gl::glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
    gl::glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
    gl::glDeleteShader(shader);
    return core::fail(core::ErrorCode::GraphicsError,
                      std::string("Program: ") + name +
                          (stage == GL_VERTEX_SHADER ? " vertex" : " fragment") +
                          " shader does not compile: " + log.data());
}

}  // namespace

const char* draw_uniform_name(DrawUniform u) noexcept
{
    switch (u)
    {
    case DrawUniform::ViewProjection: return "u_view_projection";
    case DrawUniform::Eye: return "u_eye";
    case DrawUniform::ColorMode: return "u_color_mode";
    case DrawUniform::Shading: return "u_shading";
    case DrawUniform::Flat: return "u_flat";
    case DrawUniform::BaseColor: return "u_base_color";
    case DrawUniform::WireColor: return "u_wire_color";
    case DrawUniform::Palette: return "u_palette";
    case DrawUniform::ValueRange: return "u_value_range";
    case DrawUniform::Ambient: return "u_ambient";
    case DrawUniform::Specular: return "u_specular";
    case DrawUniform::Shininess: return "u_shininess";
    case DrawUniform::Nx: return "u_nx";
    }
    return "";
}

core::Result<Program> Program::create(const char* vertex_source, const char* fragment_source,
                                      const char* name)
{
    auto vs = compile(GL_VERTEX_SHADER, vertex_source, name);
    if (!vs)
        return vs.error();
    auto fs = compile(GL_FRAGMENT_SHADER, fragment_source, name);
    if (!fs)
    {
        gl::glDeleteShader(*vs);
        return fs.error();
    }
    Program program;
    program.id_ = gl::glCreateProgram();
    gl::glAttachShader(program.id_, *vs);
    gl::glAttachShader(program.id_, *fs);
    gl::glBindFragDataLocation(program.id_, 0, "frag_color");
    gl::glLinkProgram(program.id_);
    gl::glDeleteShader(*vs);
    gl::glDeleteShader(*fs);
    GLint ok = 0;
    gl::glGetProgramiv(program.id_, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE)
    {
        GLint length = 0;
        gl::glGetProgramiv(program.id_, GL_INFO_LOG_LENGTH, &length);
        std::vector<char> log(static_cast<std::size_t>(length > 0 ? length : 1), '\0');
        gl::glGetProgramInfoLog(program.id_, static_cast<GLsizei>(log.size()), nullptr, log.data());
        return core::fail(core::ErrorCode::GraphicsError,
                          std::string("Program: ") + name + " does not link: " + log.data());
    }
    for (std::size_t u = 0; u < k_draw_uniforms; ++u)
        program.locations_[u] =
            gl::glGetUniformLocation(program.id_, draw_uniform_name(static_cast<DrawUniform>(u)));
    return program;
}

void set_draw_uniforms(const Program& program, const DrawSettings& settings,
                       const CameraMatrices& camera, float value_range)
{
    gl::glUseProgram(program.id());
    const std::array<float, 16> vp = camera.view_projection.to_float();
    gl::glUniformMatrix4fv(program.location(DrawUniform::ViewProjection), 1, GL_FALSE, vp.data());
    gl::glUniform3f(program.location(DrawUniform::Eye), static_cast<float>(camera.eye.x),
                    static_cast<float>(camera.eye.y), static_cast<float>(camera.eye.z));
    gl::glUniform1i(program.location(DrawUniform::ColorMode), static_cast<GLint>(settings.color));
    gl::glUniform1i(program.location(DrawUniform::Shading), static_cast<GLint>(settings.shading));
    gl::glUniform1i(program.location(DrawUniform::Flat), 0);
    const Rgb& b = settings.base_color;
    gl::glUniform3f(program.location(DrawUniform::BaseColor), b.r, b.g, b.b);
    const Rgb& w = settings.wire_color;
    gl::glUniform3f(program.location(DrawUniform::WireColor), w.r, w.g, w.b);
    std::array<float, 24> palette{};
    for (std::uint32_t i = 0; i < 8; ++i)
    {
        const Rgb c = owner_color(i);
        palette[i * 3] = c.r;
        palette[i * 3 + 1] = c.g;
        palette[i * 3 + 2] = c.b;
    }
    gl::glUniform3fv(program.location(DrawUniform::Palette), 8, palette.data());
    const float range =
        settings.displacement_range > 0.0F ? settings.displacement_range : value_range;
    gl::glUniform1f(program.location(DrawUniform::ValueRange), range > 0.0F ? range : 1.0F);
    gl::glUniform1f(program.location(DrawUniform::Ambient), settings.ambient);
    gl::glUniform1f(program.location(DrawUniform::Specular), settings.specular);
    gl::glUniform1f(program.location(DrawUniform::Shininess), settings.shininess);
}

Rgb owner_color(std::uint32_t owner) noexcept
{
    // Okabe-Ito's colour-blind-safe palette (black replaced by a grey).
    static constexpr std::array<Rgb, 8> k_palette{{{0.902F, 0.624F, 0.000F},
                                                   {0.337F, 0.706F, 0.914F},
                                                   {0.000F, 0.620F, 0.451F},
                                                   {0.941F, 0.894F, 0.259F},
                                                   {0.000F, 0.447F, 0.698F},
                                                   {0.835F, 0.369F, 0.000F},
                                                   {0.800F, 0.475F, 0.655F},
                                                   {0.550F, 0.550F, 0.550F}}};
    return k_palette[owner % 8U];
}

Program::~Program()
{
    if (id_ != 0U)
        gl::glDeleteProgram(id_);
}

std::string with_snippets(const char* source, std::initializer_list<const char*> snippets)
{
    std::string s(source);
    const std::string version = "#version 330 core\n";
    const std::size_t at = s.find(version);
    PLIANT_ASSERT(at != std::string::npos, "with_snippets: shader without #version 330 core");
    std::string inserted;
    for (const char* snippet : snippets)
        inserted += snippet;
    s.insert(at + version.size(), inserted);
    return s;
}

}  // namespace pliant::render
