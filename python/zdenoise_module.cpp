// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// The Python module `zdenoise` (docs/PYTHON.md), with pybind11:
//
//   zdenoise.denoise(radiance, albedo, ..., **filter_options): the library's
//       denoise() on numpy arrays (H x W x C, converted to float32);
//   zdenoise.denoise_file(input, output, **options): a whole job, as the
//       command runs it (src/job/job.h), written atomically to `output`.
//
// Options come as keyword arguments named by the recipe keys of the one
// table of options (src/job/options.cpp), with '_' for '-' (value_k), and
// are read by the recipes' own code (job::set_keyword_options()): there is
// no list of option names here, and the messages are the library's.
// Argument errors (a shape, an option) are ValueError (TypeError for a
// value of a type no option takes), as the command's usage errors exit 2;
// a job that fails (a missing file or channel, an output that is an input)
// raises zdenoise.Error, a RuntimeError, as the command exits 1. The C++
// work runs with the GIL released.

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/strutil.h>

#include <zdenoise/version.h>
#include <zdenoise/zdenoise.h>

#include "job/failure.h"
#include "job/frames.h"
#include "job/job.h"
#include "job/options.h"
#include "job/recipe.h"
#include "job/validate.h"

#include "cancel.h"

namespace py  = pybind11;
namespace job = zdenoise::job;
using json    = nlohmann::json;
using OIIO::Strutil::fmt::format;

namespace {

/// zdenoise.Error: a job failed; the message is the library's one line.
struct JobError : std::runtime_error {
    using std::runtime_error::runtime_error;
};


// ---------------------------------------------------------------------
// Keyword arguments -> the options of a job::Command.

/// The library's `text` (a message, a log line) as Python text. They quote
/// file names, whose bytes need not be UTF-8: those are written \xNN.
py::str
python_text(const std::string& text)
{
    PyObject* decoded = PyUnicode_DecodeUTF8(
        text.data(), Py_ssize_t(text.size()), "backslashreplace");
    if (!decoded)
        throw py::error_already_set();
    return py::reinterpret_steal<py::str>(decoded);
}


/// python_text() in UTF-8, for an exception's message.
std::string
message(const std::string& text)
{
    return python_text(text).cast<std::string>();
}


using zdenoise_python::Cancel;

/// The error of a failed call: Cancelled when its Cancel was set, else
/// `other` (ValueError or zdenoise.Error) with the library's message.
template<class Other>
[[noreturn]] void
raise_failure(const Cancel* cancel, const std::string& error)
{
    if (cancel && cancel->flag.load())
        throw zdenoise_python::CancelledError(message(error));
    throw Other(message(error));
}


/// The name of `value`'s type, for messages: "NoneType", "ndarray".
std::string
type_name(py::handle value)
{
    return py::str(py::type::handle_of(value).attr("__name__"))
        .cast<std::string>();
}


/// A string, path (os.PathLike) or bytes as the file system's bytes
/// (os.fsencode: a name that is not UTF-8 keeps its bytes).
std::string
fs_bytes(py::handle value)
{
    return py::module_::import("os")
        .attr("fsencode")(value)
        .cast<std::string>();
}


/// A keyword argument's value as a recipe spells it, for
/// job::set_keyword_options(): True/False, whole numbers and numbers
/// (numpy scalars too), strings and paths (os.PathLike, bytes), lists or
/// tuples (halves, layers) and dicts (an input's {"path", "channels"}).
/// A number JSON cannot hold (nan, inf, a whole number beyond a double)
/// goes as its text, which the option then refuses with its own message.
json
to_json(py::handle value, const std::string& name)
{
    const py::module_ numpy = py::module_::import("numpy");
    if (py::isinstance(value, numpy.attr("generic")))
        return to_json(value.attr("item")(), name);
    if (value.is_none())
        return nullptr;
    if (py::isinstance<py::bool_>(value))
        return value.cast<bool>();
    if (py::isinstance<py::int_>(value)) {
        try {
            return value.cast<long long>();
        } catch (const py::cast_error&) {
            // Beyond 64 bits: as a real number (which no whole-number
            // option takes: they are at most 1e6), or beyond a double.
            const double v = PyLong_AsDouble(value.ptr());
            if (!PyErr_Occurred())
                return v;
            PyErr_Clear();
            return py::str(value).cast<std::string>();
        }
    }
    if (py::isinstance<py::float_>(value)) {
        const double v = value.cast<double>();
        if (std::isfinite(v))
            return v;
        return py::str(value).cast<std::string>();
    }
    if (py::isinstance<py::str>(value) || py::isinstance<py::bytes>(value)
        || py::isinstance(value, py::module_::import("os").attr("PathLike")))
        return fs_bytes(value);
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
        json list = json::array();
        for (py::handle item : value)
            list.push_back(to_json(item, name));
        return list;
    }
    if (py::isinstance<py::dict>(value)) {
        json object = json::object();
        for (auto item : py::reinterpret_borrow<py::dict>(value)) {
            if (!py::isinstance<py::str>(item.first))
                throw py::type_error(format("{}: the keys of a dict must be "
                                            "strings",
                                            name));
            object[item.first.cast<std::string>()] = to_json(item.second,
                                                             name);
        }
        return object;
    }
    throw py::type_error(format(
        "{}: cannot take a {} (give a number, a string, a path, True or "
        "False, a list or a dict)",
        name, type_name(value)));
}


/// The keyword arguments as a JSON object; None means "not given".
json
keywords_json(const py::kwargs& kwargs)
{
    json object = json::object();
    for (auto item : kwargs) {
        const std::string name = item.first.cast<std::string>();
        if (!item.second.is_none())
            object[name] = to_json(item.second, name);
    }
    return object;
}


/// Set the options of `command` that `accepts` takes from `keywords`, or
/// raise ValueError with the library's message.
void
set_options(const json& keywords,
            const std::function<bool(const job::Option&)>& accepts,
            job::Command& command)
{
    std::string error;
    if (!job::set_keyword_options(keywords, accepts, command, error))
        throw py::value_error(message(error));
}


// ---------------------------------------------------------------------
// zdenoise.denoise(): numpy arrays.

/// The options zdenoise.denoise() takes: the filter's parameters, the
/// preset they start from, threads, and albedo-samples (the albedo is a
/// render's AOV of that many samples a pixel, to prefilter: an array has
/// no metadata to say so). A later keyword of the filter is a row of the
/// table accepted here, read from ArrayCall::command by run_array_call().
bool
array_option(const job::Option& o)
{
    return o.key
           && (o.parameter || o.kind == job::Kind::Preset
               || std::string(o.key) == "threads"
               || std::string(o.key) == "albedo-samples"
               || std::string(o.key) == "diagnostics");
}


/// Pixels as the library wants them: C-contiguous float32.
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// "480×640×3"
std::string
shape_text(const py::array& a)
{
    std::string text;
    for (py::ssize_t d = 0; d < a.ndim(); ++d)
        text += (d ? "×" : "") + std::to_string(a.shape(d));
    return a.ndim() ? text : "a scalar";
}


/// What a role's array may look like.
struct Role {
    /// "H×W×3", as the messages describe it.
    const char* expected;
    bool (*channels_ok)(py::ssize_t channels);
    /// An H×W array is taken as H×W×1.
    bool two_d = false;
};

const Role kRgb { "H×W×3", [](py::ssize_t c) { return c == 3; } };
const Role kDepth { "H×W×1 (or H×W)", [](py::ssize_t c) { return c == 1; },
                    true };
const Role kIds { "H×W×1 or H×W×2k (k id, coverage pairs; or H×W)",
                  [](py::ssize_t c) { return c == 1 || c % 2 == 0; }, true };
const Role kVariance { "H×W×1 or H×W×3 (or H×W)",
                       [](py::ssize_t c) { return c == 1 || c == 3; }, true };


/// `value` as a numpy array (np.asarray), or ValueError naming `name`.
py::array
as_array(py::handle value, const std::string& name)
{
    // (np.asarray(None) would be an array of one object.)
    py::array array;
    if (!value.is_none())
        array = py::array::ensure(value);
    if (value.is_none() || !array)
        throw py::value_error(format("{}: expected a numpy array, got {}",
                                     name, type_name(value)));
    return array;
}


/// `array` converted to float32 (a C-contiguous copy unless it is one).
FloatArray
as_float(const py::array& array, const std::string& name)
{
    FloatArray pixels = FloatArray::ensure(array);
    if (!pixels)
        throw py::value_error(format("{}: expected numbers, got an array "
                                     "of dtype {}",
                                     name,
                                     py::str(array.dtype()).cast<std::string>()));
    return pixels;
}


/// The array of a guide `role` for a radiance of `height` x `width`.
FloatArray
role_array(py::handle value, const Role& role, const std::string& name,
           py::ssize_t height, py::ssize_t width)
{
    const py::array array = as_array(value, name);
    const bool two_d      = role.two_d && array.ndim() == 2;
    if (!(array.ndim() == 3 || two_d) || array.shape(0) != height
        || array.shape(1) != width
        || !role.channels_ok(two_d ? 1 : array.shape(2)))
        throw py::value_error(format("{}: expected {} like radiance ({}×{}), "
                                     "got {}",
                                     name, role.expected, height, width,
                                     shape_text(array)));
    return as_float(array, name);
}


/// An ImageBuf over an array's pixels (no copy): H x W x C floats, with
/// OIIO's default channel names (a 4th channel of four is alpha).
OIIO::ImageBuf
wrapped(const FloatArray& pixels)
{
    const int channels = pixels.ndim() == 3 ? int(pixels.shape(2)) : 1;
    const OIIO::ImageSpec spec(int(pixels.shape(1)), int(pixels.shape(0)),
                               channels, OIIO::TypeFloat);
    // The library only reads its inputs.
    return OIIO::ImageBuf(spec, const_cast<float*>(pixels.data()));
}


/// A zdenoise.denoise() call, its arguments checked.
struct ArrayCall {
    FloatArray radiance, albedo;
    /// The guides that were given.
    std::optional<FloatArray> normal, depth, ids, variance, half_a, half_b;
    job::Command command;
    const Cancel* cancel = nullptr;
};


ArrayCall
read_array_call(py::handle radiance, py::handle albedo, py::handle normal,
                py::handle depth, py::handle ids, py::handle variance,
                py::handle halves, const py::kwargs& options)
{
    ArrayCall call;
    set_options(keywords_json(options), array_option, call.command);
    // The job's own check of threads: the arrays are its input.
    job::Job checked = call.command.job;
    checked.in.given = true;
    const std::string invalid = job::validate(checked, job::Spelling::Keyword);
    if (!invalid.empty())
        throw py::value_error(message(invalid));

    const py::array noisy = as_array(radiance, "radiance");
    if (noisy.ndim() != 3 || noisy.shape(0) < 1 || noisy.shape(1) < 1
        || noisy.shape(2) < 3)
        throw py::value_error(format("radiance: expected H×W×C with C >= 3 "
                                     "(R, G, B and any others, which are "
                                     "copied), got {}",
                                     shape_text(noisy)));
    if (noisy.shape(0) > (1 << 30) || noisy.shape(1) > (1 << 30)
        || noisy.shape(2) > (1 << 20))
        throw py::value_error(format("radiance: {} is too large an image",
                                     shape_text(noisy)));
    const py::ssize_t h = noisy.shape(0), w = noisy.shape(1);
    call.radiance       = as_float(noisy, "radiance");
    call.albedo         = role_array(albedo, kRgb, "albedo", h, w);
    if (!normal.is_none())
        call.normal = role_array(normal, kRgb, "normal", h, w);
    if (!depth.is_none())
        call.depth = role_array(depth, kDepth, "depth", h, w);
    if (!ids.is_none())
        call.ids = role_array(ids, kIds, "ids", h, w);
    if (!variance.is_none())
        call.variance = role_array(variance, kVariance, "variance", h, w);
    if (!halves.is_none()) {
        const bool tuple = py::isinstance<py::tuple>(halves);
        const bool list  = py::isinstance<py::list>(halves);
        if (!(tuple || list) || py::len(halves) != 2)
            throw py::value_error(format(
                "halves: expected a pair (A, B) of H×W×3 arrays like radiance "
                "({}×{}), got {}",
                h, w,
                tuple || list ? format("{} of {}", tuple ? "a tuple" : "a list",
                                       py::len(halves))
                              : type_name(halves)));
        const py::sequence pair = py::reinterpret_borrow<py::sequence>(halves);
        call.half_a = role_array(pair[0], kRgb, "halves[0]", h, w);
        call.half_b = role_array(pair[1], kRgb, "halves[1]", h, w);
    }
    return call;
}


/// Run a checked call: the new float32 H x W x C array, and with
/// diagnostics=True also the H x W x 4 maps of diagnostic_channels(), as a
/// pair.
py::object
run_array_call(const ArrayCall& call)
{
    const OIIO::ImageBuf radiance = wrapped(call.radiance);
    const OIIO::ImageBuf albedo   = wrapped(call.albedo);
    // The guides' images, where given.
    std::vector<OIIO::ImageBuf> images;
    images.reserve(6);
    auto guide = [&](const std::optional<FloatArray>& pixels)
        -> const OIIO::ImageBuf* {
        if (!pixels)
            return nullptr;
        images.push_back(wrapped(*pixels));
        return &images.back();
    };
    zdenoise::Guides guides;
    guides.normal    = guide(call.normal);
    guides.depth     = guide(call.depth);
    guides.object_id = guide(call.ids);
    guides.variance  = guide(call.variance);
    guides.half_a    = guide(call.half_a);
    guides.half_b    = guide(call.half_b);

    // The result is written straight into the new array.
    const std::vector<py::ssize_t> shape { call.radiance.shape(0),
                                           call.radiance.shape(1),
                                           call.radiance.shape(2) };
    py::array_t<float> result(shape);
    OIIO::ImageBuf dst(radiance.spec(), result.mutable_data());
    // The maps, when asked for: the library's image, copied out below.
    const bool want_maps = call.command.job.diagnostics;
    OIIO::ImageBuf maps_image;
    zdenoise::FilterOptions filter = call.command.job.filter;
    filter.cancel = call.cancel ? &call.cancel->flag : nullptr;
    if (want_maps)
        filter.diagnostics = &maps_image;
    bool ok = false;
    {
        py::gil_scoped_release unlocked;
        const job::Job& j = call.command.job;
        OIIO::ImageBuf clean;
        ok = j.albedo_samples == 0
             || zdenoise_python::prefilter_albedo_in_bands(
                 clean, albedo, j.albedo_samples, j.threads, filter.cancel);
        if (!ok)
            dst.errorfmt("{}", clean.geterror());
        ok = ok
             && zdenoise::denoise(dst, radiance,
                                  j.albedo_samples ? clean : albedo, guides,
                                  filter, nullptr, {}, j.threads);
    }
    if (!ok)
        raise_failure<py::value_error>(call.cancel, job::one_line(dst.geterror()));
    if (!want_maps)
        return std::move(result);
    py::array_t<float> maps(std::vector<py::ssize_t> { shape[0], shape[1], 4 });
    if (!maps_image.get_pixels(OIIO::ROI(0, int(shape[1]), 0, int(shape[0]),
                                         0, 1, 0, 4),
                               OIIO::TypeFloat, maps.mutable_data()))
        throw py::value_error(message(job::one_line(maps_image.geterror())));
    return py::make_tuple(result, maps);
}


py::object
denoise(py::object radiance, py::object albedo, py::object normal,
        py::object depth, py::object ids, py::object variance,
        py::object halves, const Cancel* cancel, py::kwargs options)
{
    ArrayCall call = read_array_call(radiance, albedo, normal, depth, ids,
                                     variance, halves, options);
    call.cancel = cancel;
    return run_array_call(call);
}


// ---------------------------------------------------------------------
// zdenoise.denoise_file(): a job.

/// A path argument (str, os.PathLike, bytes) as a string.
std::string
path_text(py::handle value, const char* name)
{
    const py::module_ os = py::module_::import("os");
    if (!py::isinstance<py::str>(value) && !py::isinstance<py::bytes>(value)
        && !py::isinstance(value, os.attr("PathLike")))
        throw py::type_error(format("{}: expected a file name (str or "
                                    "os.PathLike), got {}",
                                    name,
                                    type_name(value)));
    const std::string path = fs_bytes(value);
    if (path.empty())
        throw py::value_error(format("{}: the file name is empty", name));
    return path;
}


/// What the job did, as a dict: the filter's statistics, the time of each
/// part, how the frame was cut, and what `zdenoise -v` prints of the job.
py::dict
result_dict(const job::JobResult& result)
{
    const zdenoise::FilterStats& s = result.stats;
    py::dict d;
    d["pixels"]             = s.pixels;
    d["windows"]            = s.windows;
    d["stop_quality"]       = s.stop_quality;
    d["stop_size"]          = s.stop_size;
    d["stop_edge"]          = s.stop_edge;
    d["mean_radius"]        = s.mean_radius;
    d["radius_sum"]         = s.radius_sum;
    d["passthrough_pixels"] = s.passthrough_pixels;
    d["nonfinite_pixels"]   = s.nonfinite_pixels;
    d["read_seconds"]       = result.read_seconds;
    d["denoise_seconds"]    = result.denoise_seconds;
    d["write_seconds"]      = result.write_seconds;
    d["strips"]             = result.strips;
    d["strip_rows"]         = result.strip_rows;
    d["estimated_bytes"]    = result.estimated_bytes;
    py::list log;
    for (const std::string& line : result.log)
        log.append(python_text(line));
    d["log"] = log;
    return d;
}


/// The options zdenoise.denoise_file() takes as keywords: every option of
/// the job with a recipe key, but the input, its first argument.
bool
file_option(const job::Option& o)
{
    return o.key && std::string(o.key) != "in";
}


py::dict
denoise_file(py::object input, py::object output, bool force,
             const Cancel* cancel, py::kwargs options)
{
    job::Command command;
    set_options(keywords_json(options), file_option, command);
    // The input is read as an input option is: a path or {"path",
    // "channels"}.
    json in = json::object();
    in["in"] = py::isinstance<py::dict>(input) ? to_json(input, "input")
                                               : json(path_text(input, "input"));
    set_options(in, [](const job::Option& o) {
        return o.key && std::string(o.key) == "in";
    }, command);
    const std::string out = path_text(output, "output");
    if (job::has_frame_pattern(out))
        throw py::value_error(
            "denoise_file() writes one image, and the output names a frame "
            "pattern (#, @ or %0Nd): name the frame's file, or use the "
            "zdenoise command's --frames");
    std::string invalid = job::validate(command.job, job::Spelling::Keyword);
    if (invalid.empty())
        invalid = job::frame_problem(command.job);
    if (!invalid.empty())
        throw py::value_error(message(invalid));
    // A frame of patterned inputs (frame="1042"), with temporal its
    // neighbours within shot_range, as a recipe's.
    command.job = job::resolve_frame(command.job);
    // As the command: never replace an input unless asked.
    const std::string refused = job::output_is_input(
        command.job, out, force, job::Spelling::Keyword);
    if (!refused.empty())
        throw JobError(message(refused));
    command.job.filter.cancel = cancel ? &cancel->flag : nullptr;
    job::JobResult result;
    std::string error;
    bool ok = false;
    {
        py::gil_scoped_release unlocked;
        // Written through a temporary file renamed into place (job.h).
        ok = job::run_job_to_file(command.job, out, result, error);
    }
    if (!ok)
        raise_failure<JobError>(cancel, error);
    return result_dict(result);
}


const char* kModuleDoc = R"(zdenoise: denoise Monte Carlo path-traced renders (Zhdanov, Ershov & Voloboy 2018).

denoise(radiance, albedo, ...)   denoise numpy arrays (H x W x C)
denoise_file(input, output, ...) denoise an image file as the zdenoise
                                 command does, with its options
Error                            a job failed (RuntimeError)

Options are keyword arguments named like the recipe keys and the command's
options, with '_' for '-': eta=0.03, value_k=2, rmax=8, preset="spec".
See docs/PYTHON.md and docs/FILTER.md section 9.)";

const char* kDenoiseDoc = R"(Denoise a render given as numpy arrays, each H x W x C (rows, columns,
channels), of any numeric dtype (converted to float32). Returns a new
float32 array shaped like `radiance`.

radiance  H x W x C, C >= 3: R, G, B filtered; other channels copied
          unchanged (of exactly four, the fourth is alpha: 0 marks "no
          surface", passed through).
albedo    H x W x 3, the noise-free albedo.
normal    H x W x 3 shading normals (any space; normalised).
depth     H x W x 1 (or H x W): distance along the ray; <= 0, >= 1e9 or
          non-finite means no surface.
ids       H x W x 1 object ids, or H x W x 2k (id, coverage) pairs
          (Cryptomatte ranks).
variance  H x W x 1 or H x W x 3: the per-pixel variance of the radiance.
halves    a pair (A, B) of H x W x 3 independent half renders, for the
          variance when it is not given.

filter_options, keyword arguments:
{}
These are the command's filter options named as in recipes, with '_' for
'-' (docs/FILTER.md section 9): the parameters, the preset they start from
(preset="tuned" or "spec"), and threads (0: all cores; the result does not
depend on it). None means not given. albedo_samples=N: the albedo is a
render's AOV of N samples a pixel, prefiltered first (docs/FILTER.md
section 12). diagnostics=True: return (denoised, maps), maps H x W x 4:
radius, stop, noise, error (docs/DIAGNOSTICS.md).

cancel=zdenoise.Cancel(): its cancel(), from another thread, stops the
call, which raises zdenoise.Cancelled.

A wrong shape, dtype or option raises ValueError naming the argument.
The filter runs with the GIL released.)";

const char* kDenoiseFileDoc = R"(Denoise the image file `input` into `output` exactly as the zdenoise
command does with the same options (the same file, bit for bit): the
input's radiance denoised, every other channel and the metadata kept; the
output written to a temporary file renamed into place. An output that is
also an input is refused unless force=True.

options, keyword arguments:
{}
These are the command's options named as in recipes, with '_' for '-'
(zdenoise --help, share/zdn-format.md): albedo="albedo.exr",
halves=("a.exr", "b.exr"), mode="layers", layers=["NAME=RADIANCE:ALBEDO"],
aovs=True, eta=0.03. An input may be a path or {"path": ..., "channels":
...} (the command's :ch= selection); so may `input`. None means not given.

Returns a dict: the filter's statistics (pixels, windows, stop_quality,
stop_size, stop_edge, mean_radius, radius_sum, passthrough_pixels,
nonfinite_pixels), read_seconds, denoise_seconds, write_seconds, strips,
strip_rows, estimated_bytes, and log (what zdenoise -v prints of the job,
one line each).

A wrong option raises ValueError; a job that fails (a missing file or
channel, an output that is an input) raises zdenoise.Error with the
command's one-line message; cancel=zdenoise.Cancel(), set from another
thread, stops it (zdenoise.Cancelled, no output written). The job runs
with the GIL released.)";

/// `doc` with its "{}" replaced by the keyword names of the options
/// `accepts` takes, from the table (so the help cannot forget one), in
/// indented lines.
std::string
with_option_names(const char* doc,
                  const std::function<bool(const job::Option&)>& accepts)
{
    std::string names, line;
    for (const job::Option& o : job::options()) {
        if (!o.key || !accepts(o))
            continue;
        const std::string name = job::option_name(o, job::Spelling::Keyword);
        if (!line.empty() && line.size() + name.size() + 2 > 74) {
            names += line + ",\n";
            line.clear();
        }
        line += (line.empty() ? "    " : ", ") + name;
    }
    names += line;
    std::string text = doc;
    const size_t at  = text.find("{}");
    return text.substr(0, at) + names + text.substr(at + 2);
}


}  // namespace


PYBIND11_MODULE(zdenoise, m)
{
    // Kept for the module's life: pybind11 keeps the pointers.
    static const std::string denoise_doc = with_option_names(kDenoiseDoc,
                                                             array_option);
    static const std::string denoise_file_doc
        = with_option_names(kDenoiseFileDoc, file_option);
    m.doc()             = kModuleDoc;
    m.attr("__version__") = ZDENOISE_VERSION_STRING;
    py::register_exception<JobError>(m, "Error", PyExc_RuntimeError);
    m.attr("Error").attr("__doc__")
        = "A zdenoise job failed; the message is the command's one line.";
    zdenoise_python::add_cancel(m, m.attr("Error"));
    m.def("denoise", &denoise, py::arg("radiance"), py::arg("albedo"),
          py::arg("normal") = py::none(), py::arg("depth") = py::none(),
          py::arg("ids") = py::none(), py::arg("variance") = py::none(),
          py::arg("halves") = py::none(), py::kw_only(),
          py::arg("cancel") = py::none(), denoise_doc.c_str());
    m.def("denoise_file", &denoise_file, py::arg("input"), py::arg("output"),
          py::kw_only(), py::arg("force") = false,
          py::arg("cancel") = py::none(), denoise_file_doc.c_str());
}
