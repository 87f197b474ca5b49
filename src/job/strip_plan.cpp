// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The strip's role images: read from the files' held rows and converted
// between colour spaces.

#include "strip_plan.h"

#include <OpenImageIO/strutil.h>

#include "failure.h"

namespace zdenoise {
namespace job {

using namespace OIIO;
using OIIO::Strutil::fmt::format;

void
convert_role(const Plan& p, ImageBuf& image, const std::string& from,
             const std::string& to, const InputArg& arg)
{
    std::string err;
    if (p.managed && image.initialized()
        && !p.config.convert_rgb(image, from, to, err))
        fail(format("'{}': {}", arg.path, one_line(err)));
}


RoleImages
read_role_images(const Job& j, const Plan& p, const Strip& strip)
{
    // Images converted to the working space are copies; the others are
    // the files' rows.
    const RoleSelections& roles = p.roles;
    auto read = [&](const OptionalRole& o) {
        return o.used ? strip.image(o.selection, role_as_is(o, p))
                      : ImageBuf();
    };
    RoleImages img;
    img.radiance = strip.image(roles.radiance, p.radiance_as_is);
    if (!p.layered)
        img.albedo = strip.image(roles.albedo, p.albedo_as_is);
    img.normal   = read(roles.normal);
    img.depth    = read(roles.depth);
    img.id       = read(roles.id);
    img.variance = read(roles.variance);
    img.half_a   = read(roles.half_a);
    img.half_b   = read(roles.half_b);
    img.remodulation = read(roles.remodulation);
    img.motion       = read(roles.motion);
    if (roles.own_albedo.used)
        img.own_albedo = strip.image(roles.own_albedo.selection,
                                     p.radiance_as_is);
    img.half_a_albedo = read(roles.half_a_albedo);
    img.half_b_albedo = read(roles.half_b_albedo);
    convert_role(p, img.radiance, p.spaces.input, p.spaces.working, j.in);
    convert_role(p, img.albedo, p.spaces.albedo, p.spaces.working, j.albedo);
    convert_role(p, img.remodulation, p.spaces.albedo, p.spaces.working, j.aux);
    convert_role(p, img.own_albedo, p.spaces.input, p.spaces.working, j.in);
    convert_role(p, img.half_a, p.spaces.input, p.spaces.working, j.half_a);
    convert_role(p, img.half_b, p.spaces.input, p.spaces.working, j.half_b);
    convert_role(p, img.half_a_albedo, p.spaces.albedo, p.spaces.working, j.half_a);
    convert_role(p, img.half_b_albedo, p.spaces.albedo, p.spaces.working, j.half_b);
    return img;
}

}  // namespace job
}  // namespace zdenoise
