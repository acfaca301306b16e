#pragma once
// The library never lets PCL print: PCL's console verbosity is process-wide, set once here to
// L_ALWAYS (only messages PCL itself marks as unconditional) before the first PCL call.

namespace depthbias::panel {

// Idempotent and thread-safe; called at the entry of the functions that run PCL.
void QuietPcl();

}  // namespace depthbias::panel
