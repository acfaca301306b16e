#pragma once
// gap.json is written with the project's one JSON builder (records/json_writer.h), indented.

#include "records/json_writer.h"

namespace depthbias::gap {

using records::JsonWriter;

}  // namespace depthbias::gap
