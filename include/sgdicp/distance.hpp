#pragma once
// Forwarding header, kept for the 0.1 releases: the header now lives in its part's folder.
// Include "sgdicp/core/distance.hpp" instead; this one goes in 0.2.
#include "sgdicp/core/distance.hpp"
