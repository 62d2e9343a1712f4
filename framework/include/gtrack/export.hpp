// Symbol visibility for the framework library (built with hidden visibility).
#pragma once

#if defined(_WIN32)
#define GTRACK_API __declspec(dllexport)
#else
#define GTRACK_API __attribute__((visibility("default")))
#endif
