// Every dynamics algorithm, for convenience.
#pragma once

#include "robodiff/dynamics/aba.hpp"
#include "robodiff/dynamics/center_of_mass.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/crba.hpp"
#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/jacobian.hpp"
#include "robodiff/dynamics/kinematics.hpp"
#include "robodiff/dynamics/minv.hpp"
#include "robodiff/dynamics/regressor.hpp"
#include "robodiff/dynamics/rnea.hpp"
