# OpenImageIO and OpenColorIO as shipped in the package: the shared libraries
# of their PyPI wheels and the headers of the matching sdists, both fetched
# into .deps/ by scripts/native_deps.py (docs/packaging.md says why).
#
# The sdists carry templates for two generated headers; they are configured
# here with the values the wheels were built with (the library's namespaces
# must match the symbols it exports, or nothing links). OpenImageIO's headers
# also expect fmt under OpenImageIO/detail/fmt, which its own build copies in:
# Debian's header-only fmt takes that place.
#
# Defines Penumbra::OpenImageIO, Penumbra::OpenColorIO and PENUMBRA_FFMPEG
# (the decoder executable the tests and the package use).

set(PENUMBRA_DEPS_DIR "${CMAKE_SOURCE_DIR}/.deps" CACHE PATH
    "Where scripts/native_deps.py put OpenImageIO, OpenColorIO and ffmpeg")
set(PENUMBRA_OIIO_VERSION 3.2.2.0)
set(PENUMBRA_OCIO_VERSION 2.6.0)
set(_oiio ${PENUMBRA_DEPS_DIR}/openimageio-${PENUMBRA_OIIO_VERSION})
set(_ocio ${PENUMBRA_DEPS_DIR}/opencolorio-${PENUMBRA_OCIO_VERSION})
foreach(_stamp ${_oiio}/.complete ${_ocio}/.complete)
  if(NOT EXISTS ${_stamp})
    message(FATAL_ERROR "${_stamp} is missing: run scripts/native_deps.py (make deps does)")
  endif()
endforeach()
set(_generated ${CMAKE_BINARY_DIR}/native-deps-include)

find_package(Imath 3 REQUIRED CONFIG)  # for its version; its headers are in /usr/include
find_path(PENUMBRA_FMT_INCLUDE fmt/format.h REQUIRED)

# In a function, so the template's PROJECT_VERSION_* don't clobber ours.
function(_penumbra_configure_oiio_headers)
  string(REPLACE "." ";" _v ${PENUMBRA_OIIO_VERSION})
  list(GET _v 0 PROJECT_VERSION_MAJOR)
  list(GET _v 1 PROJECT_VERSION_MINOR)
  list(GET _v 2 PROJECT_VERSION_PATCH)
  list(GET _v 3 PROJECT_VERSION_TWEAK)
  set(PROJECT_VERSION_RELEASE_TYPE "")
  set(OIIO_USE_COMPILED_FMT_VALUE 0)
  set(PROJ_NAMESPACE OpenImageIO)
  set(PROJ_VERSION_NAMESPACE v${PROJECT_VERSION_MAJOR}_${PROJECT_VERSION_MINOR})
  set(Imath_VERSION_MAJOR ${Imath_VERSION_MAJOR})
  set(Imath_VERSION_MINOR ${Imath_VERSION_MINOR})
  set(CMAKE_CXX_STANDARD 17)  # the standard the wheel was built with
  configure_file(${_oiio}/include/OpenImageIO/oiioversion.h.in
                 ${_generated}/OpenImageIO/oiioversion.h @ONLY)
  file(GLOB _fmt_headers ${PENUMBRA_FMT_INCLUDE}/fmt/*.h)
  file(COPY ${_fmt_headers} DESTINATION ${_generated}/OpenImageIO/detail/fmt)
endfunction()

function(_penumbra_configure_ocio_headers)
  string(REPLACE "." ";" _v ${PENUMBRA_OCIO_VERSION})
  list(GET _v 0 OpenColorIO_VERSION_MAJOR)
  list(GET _v 1 OpenColorIO_VERSION_MINOR)
  list(GET _v 2 OpenColorIO_VERSION_PATCH)
  set(OpenColorIO_VERSION ${PENUMBRA_OCIO_VERSION})
  set(OpenColorIO_VERSION_RELEASE_TYPE "")
  set(OCIO_NAMESPACE OpenColorIO_v${OpenColorIO_VERSION_MAJOR}_${OpenColorIO_VERSION_MINOR})
  # OpenColorIO.h includes "OpenColorABI.h" from its own folder: configure
  # it beside copies of the other headers.
  configure_file(${_ocio}/include/OpenColorIO/OpenColorABI.h.in
                 ${_generated}/OpenColorIO/OpenColorABI.h @ONLY)
  file(GLOB _ocio_headers ${_ocio}/include/OpenColorIO/*.h)
  file(COPY ${_ocio_headers} DESTINATION ${_generated}/OpenColorIO)
endfunction()

_penumbra_configure_oiio_headers()
_penumbra_configure_ocio_headers()

# The libraries are named with three of the version's four numbers.
string(REGEX REPLACE "\\.[0-9]+$" "" _oiio_soversion ${PENUMBRA_OIIO_VERSION})
add_library(Penumbra::OpenImageIO_Util SHARED IMPORTED)
set_target_properties(Penumbra::OpenImageIO_Util PROPERTIES
  IMPORTED_LOCATION ${_oiio}/lib/libOpenImageIO_Util.so.${_oiio_soversion})
add_library(Penumbra::OpenImageIO SHARED IMPORTED)
set_target_properties(Penumbra::OpenImageIO PROPERTIES
  IMPORTED_LOCATION ${_oiio}/lib/libOpenImageIO.so.${_oiio_soversion}
  INTERFACE_INCLUDE_DIRECTORIES "${_generated};${_oiio}/include"
  INTERFACE_LINK_LIBRARIES Penumbra::OpenImageIO_Util)
# The wheel's libOpenColorIO.so has no version in its name: the package
# renames it (auditwheel) so it can never be mistaken for another copy.
add_library(Penumbra::OpenColorIO SHARED IMPORTED)
set_target_properties(Penumbra::OpenColorIO PROPERTIES
  IMPORTED_LOCATION ${_ocio}/lib/libOpenColorIO.so
  IMPORTED_SONAME libOpenColorIO.so
  INTERFACE_INCLUDE_DIRECTORIES ${_generated})

set(PENUMBRA_FFMPEG ${PENUMBRA_DEPS_DIR}/imageio-ffmpeg-0.6.0/bin/ffmpeg CACHE FILEPATH
    "The ffmpeg executable that decodes video (the package ships the same one)")
