// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
// The viewer's ImGui panels (one collapsing section per stage, docs/style.md §9): status and
// loading, display, export, material and integrator, grab, plots, session.
#include <pliant/render/draw_settings.h>

#include <imgui.h>

#include "viewer_app.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

namespace pliant::viewer
{
namespace
{

void plot(const char* label, const PlotHistory& h, const char* unit)
{
    float hi = 0.0F;
    for (float v : h.values)
        hi = std::max(hi, v);
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "%.2f %s (max %.2f)", static_cast<double>(h.latest()),
                  unit, static_cast<double>(hi));
    ImGui::PlotLines(label, h.values.data(), static_cast<int>(PlotHistory::k_size),
                     static_cast<int>(h.next), overlay, 0.0F, hi > 0.0F ? hi * 1.1F : 1.0F,
                     ImVec2(0.0F, 48.0F));
}

ImVec4 to_imvec(const render::Rgb& c)
{
    return {c.r, c.g, c.b, 1.0F};
}

const char* role_name(session::SessionRole role)
{
    switch (role)
    {
    case session::SessionRole::Master: return "master";
    case session::SessionRole::Participant: return "participant";
    case session::SessionRole::Viewer: return "viewer";
    }
    return "?";
}

}  // namespace

void Viewer::draw_panels()
{
    if (options_.hide_panels)
        return;
    ImGui::SetNextWindowPos(ImVec2(8.0F, 8.0F), ImGuiCond_FirstUseEver);
    // The window's height at its first use: an auto-fitted height (0) was measured once, before
    // the Session panel opened, and cut it off below; the full height scrolls instead.
    const float height = std::max(200.0F, ImGui::GetIO().DisplaySize.y - 16.0F);
    ImGui::SetNextWindowSize(ImVec2(340.0F, height), ImGuiCond_FirstUseEver);
    if (!ImGui::Begin("pliant view"))
    {
        ImGui::End();
        return;
    }
    // Status and loading.
    if (!status_.empty())
    {
        // Wrapped in both cases: an error names an address or a file and must be read whole.
        if (status_error_)
            ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0F, 0.45F, 0.4F, 1.0F));
        ImGui::TextWrapped("%s", status_.c_str());
        if (status_error_)
            ImGui::PopStyleColor();
    }
    if (load_)
    {
        const auto [phase, fraction] = load_->progress();
        const std::string label = load_->cancelling() ? "cancelling" : phase;
        ImGui::ProgressBar(static_cast<float>(fraction), ImVec2(-70.0F, 0.0F), label.c_str());
        ImGui::SameLine();
        ImGui::BeginDisabled(load_->cancelling());
        if (ImGui::Button("Cancel"))
            load_->cancel();
        ImGui::EndDisabled();
    }
    ImGui::Text("%.1f fps, sim t = %.2f s", 1000.0 / std::max(0.01, double{frame_ms_.latest()}),
                session_ ? session_->shown_time() : (local_ ? local_->state().time : 0.0));

    if (ImGui::CollapsingHeader("Load"))
    {
        ImGui::InputText("file", load_path_.data(), load_path_.size());
        ImGui::SliderInt("remesh level", &options_.level, 1, core::k_max_level);  // as --level
        // A load replaces the surface, and with it the session's: leave it first.
        ImGui::BeginDisabled(load_ != nullptr || load_path_[0] == '\0' || session_ != nullptr);
        if (ImGui::Button("Load mesh or .pgrid"))
            start_load(load_path_.data());
        ImGui::EndDisabled();
        if (session_)
            ImGui::TextDisabled("leave the session to load another surface");
    }

    const sim::MembraneModel* m = model();
    if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen) && m != nullptr)
    {
        const int level = m->grid().level();
        ImGui::SliderInt("display level", &display_level_, level, max_display_level(level));
        ImGui::Text("sim level %d, %zu triangles drawn", level,
                    renderer_ ? renderer_->triangle_count() : std::size_t{0});
        int color = static_cast<int>(color_);
        ImGui::Combo("colour", &color, "plain\0displacement\0owner\0");
        color_ = static_cast<render::ColorMode>(color);
        ImGui::Checkbox("wireframe", &draw_.wireframe);
        if (ImGui::Button("reset camera"))
        {
            draw_.camera.azimuth_deg = 30.0;
            draw_.camera.elevation_deg = 20.0;
            zoom_ = 1.0;
        }
        ImGui::SameLine();
        if (ImGui::Button("screenshot (P)"))
            request_screenshot(std::nullopt);
    }

    if (ImGui::CollapsingHeader("Export") && m != nullptr)
    {
        ImGui::Combo("format", &export_format_,
                     "OBJ\0PLY (binary, double)\0glTF (.gltf + .bin)\0GLB (binary glTF)\0");
        if (ImGui::Button("export (E)"))
            export_surface(std::nullopt);
        ImGui::TextWrapped(
            "Writes the simulation-level surface p = P + u N (%zu vertices) to "
            "pliant-view-NNNN in the working folder.",
            view_.positions().size());
    }

    if (ImGui::CollapsingHeader("Material and integrator") && m != nullptr)
    {
        if (session_)
        {
            const sim::MembraneSettings& s = m->settings();
            ImGui::Text("T %.3g  rho %.3g  beta %.3g  k_f %.3g", s.T, s.rho, s.beta, s.k_f);
            if (s.max_force > 0.0)
                ImGui::Text("force limit %.3g N (a longer grab acts at it)", s.max_force);
            else
                ImGui::Text("no force limit");
            ImGui::TextDisabled("(set by the session's master)");
        }
        else
        {
            ImGui::InputDouble("T [N/m]", &material_.T, 0.1, 1.0, "%.3g");
            ImGui::InputDouble("rho [kg/m2]", &material_.rho, 0.1, 1.0, "%.3g");
            ImGui::InputDouble("beta [1/s]", &material_.beta, 0.1, 1.0, "%.3g");
            ImGui::InputDouble("k_f [1/s2]", &material_.k_f, 0.5, 5.0, "%.3g");
            ImGui::Checkbox("fixed step", &material_.fixed_step);
            if (material_.fixed_step)
                ImGui::InputDouble("dt [s]", &material_.fixed_dt, 1e-4, 1e-3, "%.2e");
            else
                ImGui::InputDouble("rtol", &material_.rtol, 1e-5, 1e-4, "%.1e");
            // Float increments over the double state: ~1.6x faster steps (docs/physics.md §9).
            bool mixed = material_.precision == sim::Precision::Mixed;
            if (ImGui::Checkbox("mixed precision", &mixed))
                material_.precision = mixed ? sim::Precision::Mixed : sim::Precision::Double;
            if (ImGui::Button("apply"))
            {
                if (auto ok = local_->set_settings(material_); !ok)
                    set_status(ok.error().message, true);
                else
                    set_status("material and integrator applied", false);
            }
            ImGui::SameLine();
            if (ImGui::Button(paused_ ? "resume (space)" : "pause (space)"))
                paused_ = !paused_;
            ImGui::SameLine();
            if (ImGui::Button("rest (R)"))
                local_->reset();
        }
        float radius = static_cast<float>(grab_radius_factor_);
        if (ImGui::SliderFloat("grab radius", &radius, 0.01F, 0.5F, "%.2f x size"))
            grab_radius_factor_ = radius;
        float stiffness = static_cast<float>(grab_stiffness_scale_);
        if (ImGui::SliderFloat("grab stiffness", &stiffness, 0.05F, 20.0F, "%.2f",
                               ImGuiSliderFlags_Logarithmic))
            grab_stiffness_scale_ = stiffness;
    }

    if (ImGui::CollapsingHeader("Plots", ImGuiTreeNodeFlags_DefaultOpen))
    {
        plot("frame", frame_ms_, "ms");
        plot("step", step_ms_, "ms");
        if (session_)
        {
            plot("in", kbps_in_, "kB/s");
            plot("out", kbps_out_, "kB/s");
            plot("latency", latency_ms_, "ms");
        }
    }

    if (open_session_panel_)
    {
        ImGui::SetNextItemOpen(true);
        open_session_panel_ = false;
    }
    if (ImGui::CollapsingHeader("Session"))
    {
        if (!session_)
        {
            ImGui::InputInt("port", &host_port_);
            host_port_ = std::clamp(host_port_, 1, 65535);
            ImGui::Checkbox("exact (lockstep)", &host_exact_);
            ImGui::BeginDisabled(!surface_);
            if (ImGui::Button("host"))
                host_session(static_cast<std::uint16_t>(host_port_), host_exact_);
            ImGui::EndDisabled();
            ImGui::Separator();
            ImGui::InputText("master", join_address_.data(), join_address_.size());
            ImGui::Checkbox("as participant", &join_as_participant_);
            if (ImGui::Button("join"))
                join_session(join_address_.data(), join_as_participant_);
        }
        else
        {
            ImGui::Text("%s, id %u, %s coupling", role_name(session_->role()),
                        static_cast<unsigned>(session_->id().value),
                        session_->coupling() == session::Coupling::Exact ? "exact" : "fast");
            ImGui::Text("tick %llu, partition epoch %u",
                        static_cast<unsigned long long>(session_->shown_tick()), session_->epoch());
            // Owned node counts per peer, from the newest partition.
            std::map<std::uint16_t, std::size_t> owned;
            const auto owners = session_->owners();
            if (const session::LeafGraph* g = session_->leaf_graph(); g != nullptr)
                for (std::size_t l = 0; l < owners.size() && l < g->size(); ++l)
                    owned[owners[l].value] += g->node_count(l);
            // This peer first, then the others by id: role and name as they announced them,
            // and the link (connecting: no greeted connection yet; joining: no Ready yet, it is
            // still loading the model; streaming: its leaf states arrive).
            std::vector<session::PeerStatus> rows;
            session::PeerStatus me;
            me.id = session_->id();
            me.master = session_->role() == session::SessionRole::Master;
            me.role = session_->role() == session::SessionRole::Viewer ? net::Role::Viewer
                                                                       : net::Role::Participant;
            me.name = options_.name;  // what this peer announced (SessionSettings::name)
            rows.push_back(me);
            for (const session::PeerStatus& p : session_->peer_status())
                rows.push_back(p);
            if (ImGui::BeginTable("peers", 4))
            {
                ImGui::TableSetupColumn("peer");
                ImGui::TableSetupColumn("role");
                ImGui::TableSetupColumn("link");
                ImGui::TableSetupColumn("nodes");
                ImGui::TableHeadersRow();
                for (const session::PeerStatus& p : rows)
                {
                    const bool self = p.id == session_->id();
                    const auto it = owned.find(p.id.value);
                    const std::size_t nodes = it != owned.end() ? it->second : 0;
                    ImGui::TableNextRow();
                    ImGui::TableNextColumn();
                    ImGui::ColorButton("##c", to_imvec(render::owner_color(p.id.value)),
                                       ImGuiColorEditFlags_NoTooltip, ImVec2(12.0F, 12.0F));
                    ImGui::SameLine();
                    ImGui::Text("%u %s%s", static_cast<unsigned>(p.id.value), p.name.c_str(),
                                self ? " (me)" : "");
                    ImGui::TableNextColumn();
                    ImGui::TextUnformatted(p.master                      ? "master"
                                           : p.role == net::Role::Viewer ? "viewer"
                                                                         : "participant");
                    ImGui::TableNextColumn();
                    ImGui::TextUnformatted(self              ? "-"
                                           : !p.connected    ? "connecting"
                                           : !p.has_model    ? "joining"
                                           : p.streams_to_us ? "streaming"
                                                             : "connected");
                    if (p.rejected > 0)  // messages no honest peer sends (logged, --stats)
                    {
                        ImGui::SameLine();
                        ImGui::TextColored(ImVec4(1.0F, 0.4F, 0.3F, 1.0F), "%llu rejected",
                                           static_cast<unsigned long long>(p.rejected));
                    }
                    ImGui::TableNextColumn();
                    ImGui::Text("%zu", nodes);
                }
                ImGui::EndTable();
            }
            if (ImGui::Button(session_->role() == session::SessionRole::Master ? "end session"
                                                                               : "leave"))
                leave_session();
        }
    }
    ImGui::End();
}

}  // namespace pliant::viewer
