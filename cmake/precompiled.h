// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The third-party and standard headers most units parse, precompiled once per build
// (UNSEEN_PRECOMPILE_HEADERS, cmake/UnseenModule.cmake). Only headers whose meaning does not
// depend on a unit's own definitions belong here; every unit still includes what it uses.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>
