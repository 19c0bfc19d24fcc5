// The slab's free flights: spectral-MIS flights (pfmc), flights by the smallest extinction
// (pfmc2's bright slabs), pure absorption, and the transmittance along a straight path.
#include <algorithm>
#include <cmath>
#include "bsdflab/layered.h"
#include "bsdflab/vector_math.h"

namespace bsdflab {

double LayeredBSDF::fly(const Slab &S, double room, double cz, PCG32 &rng, double *beta, double *tr) const {
    const int C = channels();
    const double length = room / cz;
    if (!(S.sigma_s > 0)) { // pure absorption: attenuate deterministically
        absorb(S, length, beta, tr);
        return -1.0;
    }
    // Spectral MIS (one-sample, balance heuristic over channels): draw the flight with a
    // randomly chosen channel's extinction; weight each channel by its true density over
    // the channel-average density. Weights stay below C whatever the spectral contrast.
    const double u_channel = rng.uniform();
    const double u_distance = rng.uniform();
    const int k = std::min(C - 1, static_cast<int>(u_channel * C));
    const double sk = S.sigma_a[k] + S.sigma_s;
    const double t = -std::log(1.0 - u_distance) / sk;
    const bool collide = t < length;
    const double d = collide ? t : length;
    for (int c = 0; c < C; ++c) tr[c] = -(S.sigma_a[c] + S.sigma_s) * d;
    exp_array(tr, tr, C);
    double avg = 0;
    for (int c = 0; c < C; ++c) avg += collide ? (S.sigma_a[c] + S.sigma_s) * tr[c] : tr[c];
    avg /= C;
    if (!(avg > 0)) { // every channel extinct: the walk carries nothing
        for (int c = 0; c < C; ++c) beta[c] = 0.0;
        return -1.0;
    }
    for (int c = 0; c < C; ++c) beta[c] *= (collide ? S.sigma_s : 1.0) * tr[c] / avg;
    return collide ? t : -1.0;
}

// Distances drawn with density sbar exp(-sbar t), sbar = sigma_s + min_c sigma_a[c], a grey
// extinction no channel's is below: a collision at t weighs channel c by
// sigma_s exp(-sigma_t[c] t) / (sbar exp(-sbar t)) = (sigma_s / sbar) exp(-(sigma_a[c] - min) t)
// and reaching the boundary (probability exp(-sbar L)) by exp(-(sigma_a[c] - min) L):
// both <= 1, so a walk's spectral weights never grow, however many flights it has.
double LayeredBSDF::fly_min_extinction(std::size_t j, double room, double cz, PCG32 &rng, double *beta,
                                       double *tmp) const {
    const Slab &S = slabs_[j];
    const int C = channels();
    const double length = room / cz, amin = min_sigma_a_[j];
    const double sbar = S.sigma_s + amin;
    if (!(S.sigma_s > 0)) { // pure absorption: attenuate deterministically
        absorb(S, length, beta, tmp);
        return -1.0;
    }
    const double u_distance = rng.uniform();
    const double t = -std::log(1.0 - u_distance) / sbar;
    const bool collide = t < length;
    const double d = collide ? t : length;
    const double scale = collide ? S.sigma_s / sbar : 1.0;
    for (int c = 0; c < C; ++c) {
        const double extra = S.sigma_a[c] - amin;
        tmp[c] = extra > 0 ? -extra * d : 0.0; // exp(0) = 1 exactly: the least absorbed channel
    }
    exp_array(tmp, tmp, C);
    for (int c = 0; c < C; ++c) beta[c] *= scale * tmp[c];
    return collide ? t : -1.0;
}

void LayeredBSDF::absorb(const Slab &S, double length, double *beta, double *tmp) const {
    const int C = channels();
    for (int c = 0; c < C; ++c) tmp[c] = -S.sigma_a[c] * length;
    exp_array(tmp, tmp, C);
    for (int c = 0; c < C; ++c) beta[c] *= tmp[c];
}

void LayeredBSDF::transmittance(int j, double distance, double *tr) const {
    const Slab &s = slabs_[j];
    const int C = channels();
    for (int c = 0; c < C; ++c) tr[c] = -(s.sigma_a[c] + s.sigma_s) * distance;
    exp_array(tr, tr, C);
}

} // namespace bsdflab
