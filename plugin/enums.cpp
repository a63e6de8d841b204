#include "enums.hpp"

#include <cctype>

namespace py = pybind11;

namespace penumbra::bindings::detail {

std::string upper_case(std::string text) {
    for (char& c : text) c = char(std::toupper(static_cast<unsigned char>(c)));
    return text;
}

std::string not_a_member(const std::string& what, const std::string& type, const std::vector<std::string>& names,
                         const std::string& given) {
    std::string valid;
    for (std::size_t i = 0; i < names.size(); ++i)
        valid += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    return what + " must be " + valid + " (" + type + ", any case), not '" + given + "'";
}

void convert_from_str(const std::type_info& type) {
    py::detail::type_info* info = py::detail::get_type_info(type);
    if (!info)
        py::pybind11_fail("convert_from_str: the enum is not registered");
    info->implicit_conversions.emplace_back([](PyObject* object, PyTypeObject* enum_type) -> PyObject* {
        if (!PyUnicode_Check(object))
            return nullptr;  // not ours: pybind11 goes on to its TypeError
        PyObject* member = PyObject_CallOneArg(reinterpret_cast<PyObject*>(enum_type), object);
        if (!member)
            throw py::error_already_set();  // the ValueError naming the valid names, raised by the call
        return member;
    });
}

}  // namespace penumbra::bindings::detail
