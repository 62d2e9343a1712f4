// gtrack version and plugin ABI version.
//
// The project version is read from here by CMake. The plugin ABI version is
// what the loader compares before it calls anything in a plugin: bump it
// whenever a change to the public headers would break an already-built plugin
// (a virtual function added, removed or reordered in Sensor, Gripper or
// Stimulus; a change of layout of a struct that crosses the boundary).
#pragma once

#define GTRACK_VERSION_MAJOR 0
#define GTRACK_VERSION_MINOR 1
#define GTRACK_VERSION_PATCH 0
#define GTRACK_VERSION_STRING "0.1.0"

#define GTRACK_PLUGIN_ABI_VERSION 1
