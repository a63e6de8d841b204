# The two checking builds of docs/reliability.md, each in its own folder:
#
#   PENUMBRA_SANITIZE  everything (core, module, C++ tests, fuzz replays)
#                      with AddressSanitizer and UndefinedBehaviorSanitizer;
#                      UBSan stops at the first report. `make test-sanitize`
#                      (part of `make test`) builds it in build-asan with gcc.
#   PENUMBRA_FUZZ      the libFuzzer harnesses of tests/fuzz, with ASan and
#                      UBSan, the core instrumented for coverage. Needs clang
#                      (Debian's clang-14 and libclang-rt-14-dev); `make fuzz`
#                      builds it in build-fuzz.
#
# Both switch the flags on for every target of the folder, so the core, the
# module and the tests are all instrumented alike; OpenImageIO, OpenColorIO,
# Embree and TBB are prebuilt libraries and stay as they are.

option(PENUMBRA_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(PENUMBRA_FUZZ "Build the libFuzzer harnesses of tests/fuzz (clang only)" OFF)

if(PENUMBRA_SANITIZE OR PENUMBRA_FUZZ)
  set(PENUMBRA_SANITIZER_FLAGS
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  add_compile_options(${PENUMBRA_SANITIZER_FLAGS})
  add_link_options(${PENUMBRA_SANITIZER_FLAGS})
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # GCC 12 warns falsely inside libstdc++'s <regex> once ASan instruments it.
    add_compile_options(-Wno-maybe-uninitialized)
  endif()
endif()

if(PENUMBRA_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "PENUMBRA_FUZZ needs clang (libFuzzer): configure with CXX=clang++-14")
  endif()
  # Coverage instrumentation everywhere; only the harnesses link libFuzzer's main.
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
