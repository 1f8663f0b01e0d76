// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// An empty unit: the target that builds the precompiled headers (cmake/UnseenModule.cmake).
