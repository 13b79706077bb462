# The man page and the bash completion (generated at build time from the
# command's own parser, apps/help.cc), each package's copyright and changelog,
# and the three Debian packages of `cpack -G DEB` (docs/packaging.md):
#   zwidth          runtime: the command, its plugins, Table I/II, docs, man page, completion
#   libzwidth-dev   dev:     headers, static libraries, the CMake package
#   python3-zwidth  python:  the module (everything python/ installs)
# Included from the top-level CMakeLists.txt after the targets exist.

find_program(ZWIDTH_GZIP gzip)
find_program(ZWIDTH_HELP2MAN help2man)
find_program(ZWIDTH_DPKG_PARSECHANGELOG dpkg-parsechangelog)
set(ZWIDTH_CHANGELOG ${PROJECT_SOURCE_DIR}/debian/changelog)

# The changelog's latest entry dates the man page (SOURCE_DATE_EPOCH: the same
# page from the same source) and must name this version.
set(ZWIDTH_SOURCE_DATE_EPOCH "")
if(ZWIDTH_DPKG_PARSECHANGELOG)
  execute_process(COMMAND ${ZWIDTH_DPKG_PARSECHANGELOG} -l ${ZWIDTH_CHANGELOG} -S Version
                  OUTPUT_VARIABLE _version OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _rc)
  execute_process(COMMAND ${ZWIDTH_DPKG_PARSECHANGELOG} -l ${ZWIDTH_CHANGELOG} -S Timestamp
                  OUTPUT_VARIABLE ZWIDTH_SOURCE_DATE_EPOCH OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT _rc EQUAL 0 OR NOT _version STREQUAL PROJECT_VERSION)
    message(WARNING "zwidth: debian/changelog's latest entry is '${_version}', the project is ${PROJECT_VERSION}: "
                    "add an entry (dch -v ${PROJECT_VERSION}) so that the packages' changelog matches")
  endif()
endif()
set(ZWIDTH_DATE_ENV "")
if(ZWIDTH_SOURCE_DATE_EPOCH)
  set(ZWIDTH_DATE_ENV SOURCE_DATE_EPOCH=${ZWIDTH_SOURCE_DATE_EPOCH})
endif()

set(ZWIDTH_GENERATED_FILES)
# bash completion: `zwidth --bash-completion`, written through a temporary name.
set(ZWIDTH_COMPLETION ${PROJECT_BINARY_DIR}/share/bash-completion/completions/zwidth)
add_custom_command(OUTPUT ${ZWIDTH_COMPLETION}
  COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:zwidth> -DOUT=${ZWIDTH_COMPLETION} -DFLAG=--bash-completion
          -P ${PROJECT_SOURCE_DIR}/cmake/write_output.cmake
  DEPENDS zwidth ${PROJECT_SOURCE_DIR}/cmake/write_output.cmake
  COMMENT "bash completion from zwidth's option lists" VERBATIM)
list(APPEND ZWIDTH_GENERATED_FILES ${ZWIDTH_COMPLETION})
install(FILES ${ZWIDTH_COMPLETION} DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions COMPONENT runtime)

# man page: help2man on `zwidth --help-man`, one section per command. Without
# help2man (or gzip) the build goes on without the page.
set(ZWIDTH_MAN ${PROJECT_BINARY_DIR}/share/man/man1/zwidth.1)
configure_file(${PROJECT_SOURCE_DIR}/cmake/zwidth.h2m.in ${PROJECT_BINARY_DIR}/zwidth.h2m @ONLY)  # FILES: the libdir
if(ZWIDTH_HELP2MAN AND ZWIDTH_GZIP)
  add_custom_command(OUTPUT ${ZWIDTH_MAN} ${ZWIDTH_MAN}.gz
    COMMAND ${CMAKE_COMMAND} -E make_directory ${PROJECT_BINARY_DIR}/share/man/man1
    COMMAND ${CMAKE_COMMAND} -E env ${ZWIDTH_DATE_ENV}
            ${ZWIDTH_HELP2MAN} --no-info --section=1 --help-option=--help-man
            "--version-string=zwidth ${PROJECT_VERSION}"
            "--name=haptic device identification and Z-width (stable stiffness and damping) analysis"
            --include=${PROJECT_BINARY_DIR}/zwidth.h2m --output=${ZWIDTH_MAN} $<TARGET_FILE:zwidth>
    COMMAND ${ZWIDTH_GZIP} -9nkf ${ZWIDTH_MAN}
    DEPENDS zwidth ${PROJECT_BINARY_DIR}/zwidth.h2m
    COMMENT "man page zwidth(1) (help2man)" VERBATIM)
  list(APPEND ZWIDTH_GENERATED_FILES ${ZWIDTH_MAN}.gz)
  install(FILES ${ZWIDTH_MAN}.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)
else()
  message(STATUS "zwidth: no man page (needs help2man and gzip: apt-get install help2man)")
endif()

# Each package's /usr/share/doc/<package>/: the machine-readable copyright and
# the Debian changelog, gzipped without a timestamp (a native package's
# changelog.gz).
set(ZWIDTH_PACKAGE_runtime zwidth)
set(ZWIDTH_PACKAGE_dev libzwidth-dev)
set(ZWIDTH_PACKAGE_python python3-zwidth)
set(ZWIDTH_COMPONENTS runtime dev)
if(ZWIDTH_HAVE_PYTHON)
  list(APPEND ZWIDTH_COMPONENTS python)
endif()
if(ZWIDTH_GZIP)
  set(_gz ${PROJECT_BINARY_DIR}/debian/changelog.gz)
  add_custom_command(OUTPUT ${_gz}
    COMMAND ${CMAKE_COMMAND} -E copy ${ZWIDTH_CHANGELOG} ${PROJECT_BINARY_DIR}/debian/changelog
    COMMAND ${ZWIDTH_GZIP} -9nf ${PROJECT_BINARY_DIR}/debian/changelog
    DEPENDS ${ZWIDTH_CHANGELOG} VERBATIM)
  list(APPEND ZWIDTH_GENERATED_FILES ${_gz})
endif()
foreach(comp IN LISTS ZWIDTH_COMPONENTS)
  set(_doc ${CMAKE_INSTALL_DATADIR}/doc/${ZWIDTH_PACKAGE_${comp}})
  install(FILES ${PROJECT_SOURCE_DIR}/debian/copyright DESTINATION ${_doc} COMPONENT ${comp})
  if(ZWIDTH_GZIP)
    install(FILES ${_gz} DESTINATION ${_doc} COMPONENT ${comp})
  endif()
endforeach()
add_custom_target(zwidth_package_files ALL DEPENDS ${ZWIDTH_GENERATED_FILES})

# --- cpack -G DEB (from the build folder): one package per component, under /usr.
set(CPACK_PACKAGE_NAME zwidth)
set(CPACK_PACKAGE_VENDOR "zwidth")
# A placeholder address (example.org is reserved, RFC 2606) until the project has one.
set(CPACK_PACKAGE_CONTACT "zwidth maintainers <zwidth-maintainers@example.org>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
# Empty: each package's description below starts with its own synopsis, and
# CPackDeb would put this one (the project's DESCRIPTION) in front of all three.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "")
set(CPACK_STRIP_FILES ON)  # the executable, the plugins and the Python extension
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL ${ZWIDTH_COMPONENTS})
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SOURCE zwidth)  # the changelog's
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
find_program(ZWIDTH_DPKG_SHLIBDEPS dpkg-shlibdeps)
set(_shlibdeps OFF)
if(ZWIDTH_DPKG_SHLIBDEPS)
  set(_shlibdeps ON)
endif()

# (No double quotes: CPackConfig.cmake carries the text unescaped; no line may
# start with a dot, a control line in a Debian description.)
set(_about "zwidth turns a haptic device's recorded logs (text, HDF5, MATLAB
files) into a validated plant model, and into the virtual stiffness K and
damping B that its sampled control loop renders stably: its Z-width, after
Gil, Puerto, Diaz and Sanchez, On the Z-Width Limitation due to the
Vibration Modes of Haptic Interfaces. Welch frequency responses with
per-bin std, a Ceres fit of a rigid body with resonance/antiresonance
sections and a verdict on the fit, the exact stable (B, K) region per loop
delay with its delta-method std, the relay experiment simulated, checks of
haptic scenes, and exports for MATLAB/Octave and Python.")

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME zwidth)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION science)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ${_shlibdeps})
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "gnuplot-nox | gnuplot")  # zwidth run's figures
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SUGGESTS "python3-zwidth, octave-control")
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION "haptic device identification and Z-width analysis
${_about}
.
This package holds the zwidth command with its two plugins (HDF5/MATLAB
files, the fit), the paper's tables of the model and of the relay
experiments, the man page and the bash completion.")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libzwidth-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_SHLIBDEPS OFF)  # static libraries only
# What zwidthConfig.cmake finds (cmake/zwidthConfig.cmake.in): Eigen3, Ceres,
# pkg-config with fftw3 and matio, HDF5 (C and C++), nlohmann_json.
# tests/install_test.sh checks this list against the files the consumer's
# configure actually used.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "libceres-dev, libeigen3-dev (>= 3.4), libfftw3-dev, libhdf5-dev, libmatio-dev, nlohmann-json3-dev (>= 3), pkgconf | pkg-config")
set(CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS "cmake (>= 3.20)")
set(CPACK_DEBIAN_DEV_DESCRIPTION "haptic device identification and Z-width analysis - development files
${_about}
.
This package holds the C++20 headers, the static libraries (one per
module: model, ident, fit, stability, io, analysis, report) and the CMake
package: find_package(zwidth) gives the targets zwidth::<module>.")

if(ZWIDTH_HAVE_PYTHON)
  # The extension is built for one CPython (its ABI tag, e.g. cpython-311).
  math(EXPR _next_minor "${Python_VERSION_MINOR} + 1")
  set(_py "${Python_VERSION_MAJOR}.${Python_VERSION_MINOR}")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-zwidth)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SHLIBDEPS ${_shlibdeps})
  set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
      "python3 (>= ${_py}~), python3 (<< ${Python_VERSION_MAJOR}.${_next_minor}), python3-numpy")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SUGGESTS "python3-scipy, python3-matplotlib, python3-control")
  set(CPACK_DEBIAN_PYTHON_DESCRIPTION "haptic device identification and Z-width analysis - Python 3 module
${_about}
.
This package holds the Python module zwidth: the same computations on
NumPy arrays (read_log, estimate, fit, Model, ZWidth, relay, check), built
for Python ${_py}.")
endif()
include(CPack)
