# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# The library as a CMake package (docs/library.md): `cmake --install` puts the headers under
# include/pliant, one static library per module under lib, and lib/cmake/pliant/ with
# pliantConfig.cmake, whose components are the modules (find_package(pliant COMPONENTS sim)).
include(CMakePackageConfigHelpers)

install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/pliant
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development)

set(PLIANT_PACKAGE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/pliant)
# One export set per module, so that a program gets the targets of the components it asked for
# and no other (linking pliant::mesh without asking for it fails as an unknown target, not deep
# in Assimp's).
foreach(module IN LISTS PLIANT_MODULES)
    install(EXPORT pliant-${module}-targets NAMESPACE pliant:: FILE pliant-${module}-targets.cmake
            DESTINATION ${PLIANT_PACKAGE_DIR} COMPONENT development)
endforeach()

# What the modules were built with, for the config to find again.
get_property(PLIANT_PACKAGE_ENET_TARGET GLOBAL PROPERTY PLIANT_PACKAGE_ENET_TARGET)
get_property(PLIANT_PACKAGE_OSMESA GLOBAL PROPERTY PLIANT_PACKAGE_OSMESA)
if(NOT PLIANT_PACKAGE_OSMESA)
    set(PLIANT_PACKAGE_OSMESA OFF)
endif()
set(PLIANT_PACKAGE_MODULES ${PLIANT_MODULES})

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/pliantConfig.cmake.in
    ${PROJECT_BINARY_DIR}/package/pliantConfig.cmake
    INSTALL_DESTINATION ${PLIANT_PACKAGE_DIR})
# 0.x: a minor version may change the API (docs/library.md, "Versions").
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/pliantConfigVersion.cmake
    COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/package/pliantConfig.cmake
              ${PROJECT_BINARY_DIR}/package/pliantConfigVersion.cmake
        DESTINATION ${PLIANT_PACKAGE_DIR} COMPONENT development)
