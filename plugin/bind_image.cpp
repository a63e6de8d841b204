// _penumbra.image: image, sequence and video files <-> numpy float32
// (height, width, 3), row 0 at the top.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "common/error.hpp"
#include "enums.hpp"
#include "image/frame_source.hpp"
#include "image/image_io.hpp"
#include "image/video.hpp"
#include "numpy_image.hpp"

namespace py = pybind11;

namespace penumbra::bindings {

namespace {

py::dict info_to_dict(const ImageInfo& info) {
    py::dict d;
    d["width"] = info.width;
    d["height"] = info.height;
    d["channels"] = info.file_channels;
    d["subimages"] = info.subimages;
    d["format"] = info.format;
    d["colorspace"] = info.colorspace;
    d["frames_per_second"] = 0.0;
    d["is_movie"] = false;
    return d;
}

py::dict info_to_dict(const VideoInfo& info) {
    py::dict d;
    d["width"] = info.width;
    d["height"] = info.height;
    d["channels"] = 3;
    d["subimages"] = info.frame_count;
    d["format"] = info.codec;
    d["colorspace"] = "";
    d["frames_per_second"] = info.frames_per_second;
    d["is_movie"] = true;
    return d;
}

py::dict read_info(const std::string& path) {
    if (is_video_file(path)) {
        VideoInfo info;
        {
            py::gil_scoped_release release;
            info = probe_video(path);
        }
        return info_to_dict(info);
    }
    ImageInfo info;
    {
        py::gil_scoped_release release;
        info = read_image_info(path);
    }
    return info_to_dict(info);
}

py::tuple sanitize_copy(const py::array& pixels, bool clamp_negative) {
    Image image = array_to_image(pixels, "pixels");
    PixelDefects d;
    {
        py::gil_scoped_release release;
        d = sanitize(image, clamp_negative);
    }
    py::dict counts;
    counts["nan"] = d.nan;
    counts["inf"] = d.inf;
    counts["negative"] = d.negative;
    return py::make_tuple(image_to_array(std::move(image)), counts);
}

py::tuple read_frames(const std::string& path, FrameSourceKind kind, int start, int count) {
    std::unique_ptr<FrameSource> source;
    std::vector<Image> frames;
    {
        py::gil_scoped_release release;
        source = open_frames(path, kind);
        const int total = source->frame_count();
        if (start < 0 || start >= total)
            throw ArgumentError("start frame " + std::to_string(start) + " is outside 0.." +
                                std::to_string(total - 1) + " of " + source->describe());
        const int end = count < 0 ? total : std::min(total, start + count);
        for (int i = start; i < end; ++i)
            frames.push_back(source->read(i));
    }
    py::list out;
    for (auto& f : frames)
        out.append(image_to_array(std::move(f)));
    return py::make_tuple(out, source->frames_per_second());
}

void bind_ffmpeg(py::module_& m) {
    m.def("set_ffmpeg_executable", &set_ffmpeg_executable, py::arg("path"),
          "The ffmpeg program that decodes video (the add-on passes the one it ships); '' restores "
          "the default: $PENUMBRA_FFMPEG, else ffmpeg on PATH.");
    m.def("ffmpeg_executable", &ffmpeg_executable, "The ffmpeg program video is decoded with.");
}

void bind_writers(py::module_& m) {
    m.def("write_exr", [](const std::string& path, const py::array& pixels, bool half, const std::string& colorspace) {
        Image image = array_to_image(pixels, "pixels");
        py::gil_scoped_release release;
        write_exr(path, image, half ? ExrPrecision::half : ExrPrecision::full, colorspace);
    }, py::arg("path"), py::arg("pixels"), py::arg("half") = true, py::arg("colorspace") = "",
    "Writes (height, width[, channels]) pixels to OpenEXR atomically, recording `colorspace` in the header.");

    m.def("write_png16", [](const std::string& path, const py::array& pixels, const std::string& colorspace) {
        Image image = array_to_image(pixels, "pixels");
        py::gil_scoped_release release;
        write_png16(path, image, colorspace);
    }, py::arg("path"), py::arg("pixels"), py::arg("colorspace") = "",
    "Writes pixels as a 16-bit PNG atomically (values clamped to [0, 1]), recording `colorspace`.");
}

}  // namespace

void bind_image(py::module_& m) {
    bind_enum<FrameSourceKind>(m, "FrameSourceKind", "kind",
        {{"AUTO", FrameSourceKind::automatic}, {"IMAGE", FrameSourceKind::single_image},
         {"SEQUENCE", FrameSourceKind::sequence}, {"VIDEO", FrameSourceKind::video}},
        "What a path is read as. AUTO: a video for a movie file (by extension), a sequence when the name has a "
        "frame number and neighbours exist, else one image.");
    bind_ffmpeg(m);

    m.def("read_info", &read_info, py::arg("path"),
    "Header of an image or video: width, height, channels, subimages (video frames), format, "
    "colorspace recorded in the file, frames_per_second.");

    m.def("read", [](const std::string& path, int frame) {
        Image image;
        {
            py::gil_scoped_release release;
            image = is_video_file(path) ? VideoReader(path).read(frame) : read_image(path, frame);
        }
        return image_to_array(std::move(image));
    }, py::arg("path"), py::arg("frame") = 0,
    "Reads an image (or frame `frame` of a video) as float32 (height, width, 3), row 0 at the top. "
    "Grey images are copied to R, G, B; alpha is dropped; NaN/Inf are kept (see sanitize).");

    bind_writers(m);

    m.def("sanitize", &sanitize_copy, py::arg("pixels"), py::arg("clamp_negative") = true,
    "Returns (clean copy, counts): NaN and Inf become 0, negatives too if clamp_negative.");

    m.def("find_sequence", [](const std::string& first_frame) {
        SequenceFiles files;
        {
            py::gil_scoped_release release;
            files = find_sequence(first_frame);
        }
        return py::make_tuple(files.paths, files.numbers);
    }, py::arg("first_frame"),
    "The files of the numbered sequence `first_frame` starts (paths, frame numbers); an error names missing frames.");

    m.def("read_frames", &read_frames, py::arg("path"), py::arg("kind") = FrameSourceKind::automatic,
          py::arg("start") = 0, py::arg("count") = -1,
    "Reads frames of an image, a numbered sequence or a video: (list of (H, W, 3) arrays, frames per second).");

    bind_image_environment(m);
}

}  // namespace penumbra::bindings
