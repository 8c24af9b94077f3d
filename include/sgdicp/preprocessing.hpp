#pragma once
// Forwarding header, kept for the 0.1 releases: preprocessing is now split by part. Include
// what you use instead; this one goes in 0.2.
#include "sgdicp/points/random_downsample.hpp"
#include "sgdicp/points/voxel_grid.hpp"
#include "sgdicp/surfaces/normals.hpp"
#include "sgdicp/surfaces/prepare_reference.hpp"
#include "sgdicp/surfaces/voxel_surfaces.hpp"
