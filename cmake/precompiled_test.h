// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The tests' precompiled headers: the library units' (precompiled.h) and GoogleTest.
#pragma once

#include "precompiled.h"

#include <gtest/gtest.h>
