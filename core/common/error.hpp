// Errors that cross the library boundary. Every failure a user can cause
// (bad file, bad argument, unknown colour space) is a penumbra::Error whose
// message says what was wrong and what to do; the Python bindings turn it
// into a Python exception, so nothing escapes into Blender as a crash.
#pragma once

#include <stdexcept>
#include <string>

namespace penumbra {

// A problem with the caller's input: a file, an argument, a setting.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// A file that is missing, unreadable, truncated or of the wrong format.
class IoError : public Error {
public:
    using Error::Error;
};

// An argument outside its documented range (maps to Python's ValueError).
class ArgumentError : public Error {
public:
    using Error::Error;
};

// Long work stopped because the progress callback asked it to.
class Cancelled : public Error {
public:
    Cancelled() : Error("cancelled by the user") {}
};

}  // namespace penumbra
