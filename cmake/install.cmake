# Install and export (issue 16): `cmake --install build [--prefix P]` puts the CLI, the static and
# the shared library, the public headers, the CMake package (orthomech::orthomech), a pkg-config
# file, the docs, the bundled mechanisms and the Python module (python/) in the GNUInstallDirs
# places; cmake/debian.cmake packages the same tree.
include(CMakePackageConfigHelpers)
# `make install` and cpack install what is built, and do not build everything first (the tests
# run cpack in a built tree; `cmake --install` never builds).
set(CMAKE_SKIP_INSTALL_ALL_DEPENDENCY ON)
set(ORTHOMECH_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/orthomech)
set(ORTHOMECH_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/orthomech)
set(ORTHOMECH_INSTALL_PYTHONDIR lib/python3/dist-packages CACHE STRING
    "where the Python package orthomech is installed (relative to the prefix)")

install(TARGETS orthomech RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS orthomech_shared EXPORT orthomech-targets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} NAMELINK_SKIP)
install(TARGETS orthomech_shared LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} NAMELINK_ONLY)
# The static archive for static linking through pkg-config (`pkg-config --static --libs`): its
# private dependencies (Ipopt, NLopt, yaml-cpp, Cairo, ...) are not CMake-exportable targets.
install(TARGETS orthomech_lib ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/orthomech ${ORTHOMECH_GENERATED_INCLUDE}/orthomech
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT orthomech-targets NAMESPACE orthomech:: DESTINATION ${ORTHOMECH_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/orthomech-config.cmake.in
                              ${PROJECT_BINARY_DIR}/orthomech-config.cmake
                              INSTALL_DESTINATION ${ORTHOMECH_INSTALL_CMAKEDIR}
                              PATH_VARS ORTHOMECH_INSTALL_DATADIR)
# 0.x: a minor version may change the interface, so find_package(orthomech 0.1) takes 0.1.*.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/orthomech-config-version.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/orthomech-config.cmake
              ${PROJECT_BINARY_DIR}/orthomech-config-version.cmake
        DESTINATION ${ORTHOMECH_INSTALL_CMAKEDIR})
# The prefix relative to the .pc file: the same file works wherever the tree is installed.
file(RELATIVE_PATH ORTHOMECH_PC_PREFIX_REL /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" ORTHOMECH_PC_PREFIX_REL "${ORTHOMECH_PC_PREFIX_REL}")
set(ORTHOMECH_PC_MPI "")
if(MPI_CXX_FOUND)
  set(ORTHOMECH_PC_MPI " ompi-cxx")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/orthomech.pc.in ${PROJECT_BINARY_DIR}/orthomech.pc
               @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/orthomech.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/CHANGELOG.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/mechanisms DESTINATION ${ORTHOMECH_INSTALL_DATADIR}
        FILES_MATCHING PATTERN "*.yaml" PATTERN "*.md")
