// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The roles' defaults from the files' conventions (role_defaults.h).

#include "role_defaults.h"

#include <cstdlib>

#include <OpenImageIO/strutil.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

/// Fill in the defaults of the convention the input follows.
void
apply_defaults(Job& j, const Convention& conv, std::vector<std::string>& log)
{
    if (conv.name.empty())
        return;
    log.push_back(format("'{}' is a {}", j.in.path, conv.name));
    if (j.in.channels.empty())
        j.in.channels = conv.beauty;
    auto pick = [&](InputArg& arg, bool disabled, const std::string& sel) {
        if (!arg.given && !disabled && !sel.empty())
            arg = { j.in.path, sel, true };
    };
    pick(j.albedo, false, conv.albedo);
    pick(j.normal, j.no_normal, conv.normal);
    pick(j.depth, j.no_depth, conv.depth);
    pick(j.id, j.no_id, conv.id);
    pick(j.motion, j.temporal == 0 || j.static_camera, conv.motion);
}


/// A role given as a file of its own without a :ch= selection takes what
/// that file's convention names for the role (a Cycles multilayer file's
/// Denoising Albedo, Denoising Normal, Combined for a half), as --in does.
/// A file of several layers whose convention names nothing for the role
/// and which has no plain channels for it is refused with its layers
/// listed: never read by whichever channels end in the role's names (a
/// Cycles file's CryptoObject00.r, g, b).
void
apply_file_defaults(Job& j, InputFiles& files)
{
    const struct {
        InputArg* arg;
        Role role;
        std::string Convention::*named;
    } roles[] = { { &j.albedo, Role::Albedo, &Convention::albedo },
                  { &j.normal, Role::Normal, &Convention::normal },
                  { &j.depth, Role::Depth, &Convention::depth },
                  { &j.id, Role::ObjectId, &Convention::id },
                  { &j.variance, Role::Variance, nullptr },
                  { &j.half_a, Role::Radiance, &Convention::beauty },
                  { &j.half_b, Role::Radiance, &Convention::beauty },
                  { &j.motion, Role::Motion, &Convention::motion } };
    for (const auto& r : roles) {
        if (!r.arg->given || !r.arg->channels.empty())
            continue;
        const std::vector<std::string>& names
            = files.header(r.arg->path).channelnames;
        const Convention c = detect_convention(names);
        if (r.named && !(c.*r.named).empty()) {
            r.arg->channels = c.*r.named;
            continue;
        }
        if (layer_paths(names).size() < 2)
            continue;
        std::vector<int> idx;
        std::string err;
        bool plain = select_channels(names, "", r.role, idx, err);
        for (int i : idx)
            plain = plain && names[size_t(i)].find('.') == std::string::npos;
        if (!plain)
            fail(format("{} '{}': no {} by a convention among its layers "
                        "({}); choose one with :ch=",
                        role_name(r.role), r.arg->path, role_name(r.role),
                        layers_text(names)));
    }
}


/// --aux: its guides replace the --in file's (not those given by flag or
/// disabled), and its albedo is the albedo when the job has none or the
/// auxiliary one demodulates; otherwise it is returned in `remodulation`
/// (its selection), to remodulate. Before the --in file's defaults.
void
apply_aux(Job& j, InputFiles& files, AuxConvention& aux,
          std::string& remodulation, std::vector<std::string>& log)
{
    check_same_shot(files, j.aux.path, j.in.path);
    const InputHeader& h = files.header(j.aux.path);
    std::string err;
    if (!detect_aux(h.channelnames, aux, err))
        fail(format("aux '{}': {}", j.aux.path, err));
    if (!j.aux.channels.empty())
        aux.albedo = j.aux.channels;
    log.push_back(format("'{}' is the auxiliary image: a {}", j.aux.path,
                         aux.name));
    auto pick = [&](InputArg& arg, bool disabled, const std::string& sel) {
        if (!arg.given && !disabled && !sel.empty())
            arg = { j.aux.path, sel, true };
    };
    pick(j.normal, j.no_normal, aux.normal);
    pick(j.depth, j.no_depth, aux.depth);
    pick(j.id, j.no_id, aux.id);
    const char* how = std::getenv("ZDENOISE_AUX_DEMODULATE");
    if (how && std::string(how) == "aux")
        j.aux_demodulation = AuxDemodulation::Aux;
    else if (how && std::string(how) == "render")
        j.aux_demodulation = AuxDemodulation::Render;
    if (j.aux_demodulation == AuxDemodulation::Aux)
        pick(j.albedo, false, aux.albedo);
    if (!j.albedo.given
        && detect_convention(files.header(j.in.path).channelnames)
               .albedo.empty())
        pick(j.albedo, false, aux.albedo);
    if (!(j.albedo.path == j.aux.path && j.albedo.channels == aux.albedo))
        remodulation = aux.albedo;
}


}  // namespace job
}  // namespace zdenoise
