#pragma once
// Forwarding header, kept for the 0.1 releases: the header now lives in its part's folder.
// Include "sgdicp/odometry/odometry.hpp" instead; this one goes in 0.2.
#include "sgdicp/odometry/odometry.hpp"
