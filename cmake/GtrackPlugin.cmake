# gtrack_add_plugin(NAME KIND sensor|gripper|stimulus SOURCES ...)
#
# Builds one runtime-loaded gtrack plugin: a shared library with hidden
# visibility, linked to the framework, placed where gtrack searches for plugins.
# Used for the built-in plugins and, through find_package(gtrack), by plugin
# authors out of tree.
function(gtrack_add_plugin name)
  cmake_parse_arguments(ARG "NO_EXPORT_CHECK" "KIND;OUTPUT_DIRECTORY" "SOURCES" ${ARGN})
  if(NOT ARG_KIND MATCHES "^(sensor|gripper|stimulus)$")
    message(FATAL_ERROR "gtrack_add_plugin(${name}): KIND must be sensor, gripper or stimulus, got '${ARG_KIND}'")
  endif()
  # The name is the library's file name part, libgtrack_<name>.so, and what
  # a config's plugin key gives: the loader's rule.
  if(NOT name MATCHES "^[A-Za-z0-9_-]+$")
    message(FATAL_ERROR "gtrack_add_plugin(${name}): the name must be letters, digits, '_' and '-' (the config's "
                        "plugin key and the file libgtrack_<name>.so)")
  endif()
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "gtrack_add_plugin(${name}): SOURCES is empty")
  endif()
  add_library(${name} MODULE ${ARG_SOURCES})
  if(TARGET gtrack::framework)
    target_link_libraries(${name} PRIVATE gtrack::framework)
  else()
    target_link_libraries(${name} PRIVATE gtrack_framework)
  endif()
  set_target_properties(${name} PROPERTIES
    PREFIX "libgtrack_"
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    CXX_STANDARD 20
    CXX_STANDARD_REQUIRED ON)
  # GTRACK_PLUGIN checks its name and interface against these at compile time.
  target_compile_definitions(${name} PRIVATE GTRACK_PLUGIN_KIND_${ARG_KIND}=1 GTRACK_PLUGIN_TARGET="${name}")
  # A plugin's terms run hundreds of times a frame: optimised even when the
  # project sets no build type.
  if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
    target_compile_options(${name} PRIVATE -O2)
  endif()
  # A missing symbol is a link error now rather than a load error later;
  # so is a library without GTRACK_PLUGIN, whose two exports the loader
  # looks for (NO_EXPORT_CHECK: the loader's tests of broken libraries).
  if(NOT APPLE)
    target_link_options(${name} PRIVATE -Wl,--no-undefined)
    if(NOT ARG_NO_EXPORT_CHECK)
      target_link_options(${name} PRIVATE -Wl,--require-defined=gtrack_plugin_info
                          -Wl,--require-defined=gtrack_plugin_create)
    endif()
  endif()
  if(ARG_OUTPUT_DIRECTORY)
    set_target_properties(${name} PROPERTIES LIBRARY_OUTPUT_DIRECTORY "${ARG_OUTPUT_DIRECTORY}")
  elseif(DEFINED GTRACK_PLUGIN_OUTPUT_DIR)
    set_target_properties(${name} PROPERTIES LIBRARY_OUTPUT_DIRECTORY "${GTRACK_PLUGIN_OUTPUT_DIR}")
  endif()
  if(DEFINED GTRACK_PLUGIN_SUBDIR AND NOT GTRACK_PLUGIN_EXTERNAL)
    install(TARGETS ${name} LIBRARY DESTINATION "${GTRACK_PLUGIN_SUBDIR}")
  endif()
endfunction()
