#pragma once
// Forwarding header, kept for the 0.1 releases: the header now lives in its part's folder.
// Include "sgdicp/index/nearest_neighbor.hpp" instead; this one goes in 0.2.
#include "sgdicp/index/nearest_neighbor.hpp"
