// The measures of a sample held by walls (Model::Sample, the SAMPLE command): a triaxial or an
// oedometer test between platens, its sides a cylinder or two pairs of planes. The strains are
// compression positive and referred to the sample as it stood when declared (or reset), as PFC's
// triaxial examples report them:
//   axial strain        ea = 1 - h / h0                       h: the platens' distance
//   volumetric strain   ev = 1 - V / V0,  V = A h             A: pi r^2, or the product of the
//                                                                 two pairs' distances
//   sigma1              the platens' normal forces (their mean) over A
//   sigma3              the sides' normal forces over their area: a cylinder's over 2 pi r h, a
//                       pair of planes' (their mean) over the other pair's distance times h; the
//                       mean of the two pairs
//   q = sigma1 - sigma3,  p = (sigma1 + 2 sigma3) / 3
// A wall's normal force is that of the last force pass (Wall::normal_force, compression > 0).
#pragma once

#include <string>

#include "model/model.hpp"

namespace trubal {

struct SampleMeasures {
  double height = 0, area = 0, volume = 0;
  double axial = 0, volumetric = 0;
  double sigma1 = 0, sigma3 = 0, q = 0, p = 0;
};

// The measures now; NaN where a wall of the sample is gone.
SampleMeasures sample_measures(const Model& model);

// What is wrong with a sample's walls ("" when nothing is): they must exist, the platens be planes
// or polygons facing each other, a cylinder's axis lie along the platens' normal, each pair of
// sides face each other across the platens' normal, and the height and the cross-section be
// positive.
std::string check_sample(const Model& model, const Sample& sample);

// The sample as it stands now taken as the reference (height0, area0).
void reset_sample(const Model& model, Sample& sample);

}  // namespace trubal
