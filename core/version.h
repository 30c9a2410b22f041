// rtlab — which commit this binary was built from (cmake/commit_stamp.cmake writes it at every
// build). RTLAB_COMMIT, defined by the build for rtlab_core and its users, calls it.
#pragma once

namespace rt {

// "3680365ab12c", "3680365ab12c-dirty" (tracked files changed), or "unknown" (no git).
const char* buildCommit();

}  // namespace rt
