// What the three C++ examples share: the usage line and the two error tiers
// of zwidth (model/error.h): InputError (the input is wrong, exit 2) and any
// other error (exit 1), printed on standard error.
#pragma once

#include <cstdio>
#include <exception>

#include <zwidth/model/error.h>

template <class Body>
int RunExample(int argc, char** argv, int min_args, const char* usage, Body body) {
  if (argc < min_args) {
    std::fprintf(stderr, "usage: %s %s\n", argv[0], usage);
    return 2;
  }
  try {
    return body();
  } catch (const zwidth::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
