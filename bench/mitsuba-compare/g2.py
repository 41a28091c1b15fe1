"""A Mitsuba BSDF plugin `roughconductor_g2corr`: Mitsuba's `roughconductor` with the
height-correlated Smith masking-shadowing G2 = 1 / (1 + Λ(ωi) + Λ(ωo)) that frepray uses
(Heitz 2014) instead of Mitsuba's separable G1(ωi)·G1(ωo). Sampling and pdf are the
built-in's (visible normals); only the value changes, by the factor G2_corr / G2_sep.

A diagnostic for compare.py --g2 correlated: it aligns the one BSDF convention the two
renderers do not share, so that what remains of a disagreement is something else.
"""

import drjit as dr
import mitsuba as mi


def register():
    """Registers the plugin for the current variant (mi.BSDF is the variant's class)."""

    class RoughConductorG2Corr(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            inner = mi.Properties("roughconductor")
            for key in ("distribution", "alpha", "eta", "k"):
                inner[key] = props[key]
            self.inner = mi.PluginManager.instance().create_object(inner)
            self.distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, props["alpha"], True)
            self.m_flags = self.inner.m_flags
            self.m_components = [self.inner.m_flags]

        def _ratio(self, wi, wo):
            """G2_corr / G2_sep for the half vector of wi, wo (local frame)."""
            m = dr.normalize(wi + wo)
            gi, go = self.distr.smith_g1(wi, m), self.distr.smith_g1(wo, m)
            ok = (gi > 0) & (go > 0)
            gi, go = dr.select(ok, gi, 1), dr.select(ok, go, 1)  # no 1/0 where masked
            corr = 1 / (1 / gi + 1 / go - 1)  # Λ = 1/G1 − 1
            return dr.select(ok, corr / (gi * go), 0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs, weight = self.inner.sample(ctx, si, sample1, sample2, active)
            return bs, weight * self._ratio(si.wi, bs.wo)

        def eval(self, ctx, si, wo, active=True):
            return self.inner.eval(ctx, si, wo, active) * self._ratio(si.wi, wo)

        def pdf(self, ctx, si, wo, active=True):
            return self.inner.pdf(ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            value, pdf = self.inner.eval_pdf(ctx, si, wo, active)
            return value * self._ratio(si.wi, wo), pdf

        def traverse(self, callback):
            pass

        def to_string(self):
            return "RoughConductorG2Corr[]"


    mi.register_bsdf("roughconductor_g2corr", lambda props: RoughConductorG2Corr(props))
