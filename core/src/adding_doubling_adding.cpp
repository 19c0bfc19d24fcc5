// Adding for the adding-doubling solve (adding_doubling_parts.h): the stack's reflection
// from the base up, and for a two-sided stack all four of its operators.
#include "adding_doubling_parts.h"

namespace bsdflab::ad {

Op inner_reflection(const std::vector<BoundaryOperators> &below, const std::vector<SlabOperators> &slabs,
                    const Sizes &s, int c, int m, const Grid &g) {
    const std::size_t K = slabs.size();
    Op R = below[K].op(below[K].Rt, s, c, m);
    for (std::size_t j = K; j-- > 0;) {
        R = slabs[j].reflect_over(c, m, g, R);
        if (j >= 1) R = reflect_over(below[j].layer(s, c, m), R, g);
    }
    return R;
}

LayerOperators stack_operators(const TopOperators &top, const std::vector<BoundaryOperators> &below,
                               const std::vector<SlabOperators> &slabs, const Sizes &s, int c, int m,
                               const Grid &g) {
    const std::size_t K = slabs.size();
    Op identity;
    identity.D.assign(s.N, 1.0);
    LayerOperators S{Op(), identity, Op(), identity};
    S.Rb = top.rb(s, c, m);
    for (std::size_t j = 0; j < K; ++j) {
        S = add_layers(S, slabs[j].layer(c, m, g), g);
        const BoundaryOperators &B = below[j + 1];
        LayerOperators L =
            j + 1 < K ? B.layer(s, c, m) : LayerOperators{B.op(B.Rt, s, c, m), identity, Op(), identity};
        S = add_layers(S, L, g);
    }
    return S;
}

} // namespace bsdflab::ad
