// The core's enums as Python enums, all registered by one helper, bind_enum.
//
// Members are named with the add-on's Blender enum identifiers in UPPER_CASE
// (lights.Projection.MIRROR_BALL is the add-on's mapping 'MIRROR_BALL'), and
// every enum is also constructible from a str, in any case:
// lights.Projection("mirror_ball") is lights.Projection.MIRROR_BALL, and a
// function that takes the enum takes the str as well. So callers keep passing
// Blender's identifiers while the core only ever sees enums. A name that is
// not a member raises ValueError naming the argument and the valid names:
//   mapping must be EQUIRECTANGULAR, HEMISPHERE_POLAR, FISHEYE or MIRROR_BALL
//   (lights.Projection, any case), not 'cube'
#pragma once

#include <pybind11/pybind11.h>

#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

namespace penumbra::bindings {

namespace detail {

std::string upper_case(std::string text);

// The ValueError text above; `type` is the enum's Python name, e.g. "lights.Projection".
std::string not_a_member(const std::string& what, const std::string& type, const std::vector<std::string>& names,
                         const std::string& given);

// A str passed where the bound C++ type `type` is expected is converted by
// calling the Python type with it. This is py::implicitly_convertible<py::str,
// E>() with one difference: pybind11's version swallows the constructor's
// ValueError and reports "incompatible function arguments" (a TypeError that
// names no valid value); this one lets the ValueError through.
void convert_from_str(const std::type_info& type);

}  // namespace detail

// Registers `E` as scope.<name>, one member per (NAME, value) pair, and makes
// it constructible from a str as described above. `what` is the argument
// name callers know it by ("mapping", "below_horizon"), used in the error.
template <class E>
pybind11::enum_<E> bind_enum(pybind11::module_& scope, const char* name, const char* what,
                             std::vector<std::pair<std::string, E>> members, const char* doc) {
    namespace py = pybind11;
    py::enum_<E> e(scope, name, doc);
    std::vector<std::string> names;
    for (const auto& [member, value] : members) {
        e.value(member.c_str(), value);
        names.push_back(member);
    }
    const std::string module_name = py::str(scope.attr("__name__"));
    const std::string type = module_name.substr(module_name.rfind('.') + 1) + "." + name;
    e.def(py::init([members, names, type, what = std::string(what)](const std::string& given) {
        const std::string key = detail::upper_case(given);
        for (const auto& [member, value] : members)
            if (member == key) return value;
        throw py::value_error(detail::not_a_member(what, type, names, given));
    }), py::arg("name"), "The member called `name`, in any case.");
    detail::convert_from_str(typeid(E));
    return e;
}

}  // namespace penumbra::bindings
