// What nearly every test includes, precompiled once and reused by every test target
// (cmake/Hdr4dHelpers.cmake, HDR4D_PCH): the libraries' list plus GoogleTest.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "library.h"
