//! The glare indices of a view from its glare sources, as Radiance's
//! `evalglare` 3.05 computes them (Wienold and Christoffersen 2006 for
//! DGP; Hopkinson's DGI; CIE 117 for UGR; Einhorn's CGI; the IES VCP), and
//! the Guth position index that weighs a source by where it sits in the
//! field of view.

/// One glare source as the indices see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    /// Mean luminance L, cd/m².
    pub luminance: f64,
    /// Solid angle ω, sr.
    pub solid_angle: f64,
    /// Guth's position index P.
    pub position_index: f64,
}

/// Guth's position index of a direction (camera frame: x right, y up, z
/// ahead): 1 on the line of sight, growing off it, faster below. Above
/// the line of sight the IES handbook's fit of Guth's table in the
/// angle off the axis σ and the azimuth τ from straight up; below it,
/// Iwata and Osterhaus's (CIE 2010) in β = atan(tan σ·√(1 + 0.3225
/// cos²τ)), as evalglare 3.02 and later; at most 16, as evalglare caps it.
pub fn position_index(direction: [f64; 3]) -> f64 {
    let [x, y, z] = direction;
    let norm = (x * x + y * y + z * z).sqrt();
    if norm == 0.0 {
        return 1.0;
    }
    let sigma = libm::acos((z / norm).clamp(-1.0, 1.0));
    let side = (x * x + y * y).sqrt();
    let tau = if side > 0.0 {
        libm::acos((y / side).clamp(-1.0, 1.0))
    } else {
        0.0
    };
    let (sigma_deg, tau_deg) = (sigma.to_degrees(), tau.to_degrees());
    let p = if y < 0.0 {
        let c = libm::cos(tau);
        let beta = libm::atan(libm::tan(sigma) * (1.0 + 0.3225 * c * c).sqrt()).to_degrees();
        libm::exp(6.49e-3 * beta + 21e-5 * beta * beta)
    } else {
        let t = tau_deg;
        libm::exp(
            (35.2 - 0.31889 * t - 1.22 * libm::exp(-2.0 * t / 9.0)) * 1e-3 * sigma_deg
                + (21.0 + 0.26667 * t - 0.002963 * t * t) * 1e-5 * sigma_deg * sigma_deg,
        )
    };
    p.min(16.0)
}

/// Σ L²·ω/P² over the sources: the sum UGR, CGI and DGP share.
fn contrast_sum(sources: &[Seen]) -> f64 {
    sources
        .iter()
        .map(|s| {
            let l = s.luminance / s.position_index;
            l * l * s.solid_angle
        })
        .sum()
}

/// Daylight glare probability (Wienold and Christoffersen 2006):
/// 5.87·10⁻⁵·E_v + 0.092·log₁₀(1 + Σ L²ω/(E_v^1.87·P²)) + 0.159, at most 1.
pub fn dgp(vertical_illuminance: f64, sources: &[Seen]) -> f64 {
    let ev = vertical_illuminance;
    let mut dgp = 5.87e-5 * ev + 0.159;
    if !sources.is_empty() && ev > 0.0 {
        dgp += 0.092 * libm::log10(1.0 + contrast_sum(sources) / libm::pow(ev, 1.87));
    }
    dgp.min(1.0)
}

/// Daylight glare index (Hopkinson), as evalglare sums it over sources:
/// 10·log₁₀ Σ 0.478·L^1.6·(ω/P²)^0.8 / (L_b + 0.07·√ω·L).
pub fn dgi(background: f64, sources: &[Seen]) -> f64 {
    let sum: f64 = sources
        .iter()
        .map(|s| {
            let omega = s.solid_angle / (s.position_index * s.position_index);
            0.478 * libm::pow(s.luminance, 1.6) * libm::pow(omega, 0.8)
                / (background + 0.07 * s.solid_angle.sqrt() * s.luminance)
        })
        .sum();
    10.0 * libm::log10(sum)
}

/// Unified glare rating (CIE 117): 8·log₁₀(0.25/L_b · Σ L²ω/P²).
pub fn ugr(background: f64, sources: &[Seen]) -> f64 {
    8.0 * libm::log10(0.25 / background * contrast_sum(sources))
}

/// CIE glare index (Einhorn): 8·log₁₀(2·(1 + E_d/500)/E_v · Σ L²ω/P²).
pub fn cgi(vertical_illuminance: f64, direct_illuminance: f64, sources: &[Seen]) -> f64 {
    8.0 * libm::log10(
        2.0 * (1.0 + direct_illuminance / 500.0) / vertical_illuminance * contrast_sum(sources),
    )
}

/// The discomfort glare rating behind VCP (IES):
/// (Σ 0.5·L·(20.4ω + 1.52ω^0.2 − 0.075)/(P·L_a^0.44))^(n^−0.0914), with
/// L_a the view's mean luminance.
pub fn dgr(mean_luminance: f64, sources: &[Seen]) -> f64 {
    let sum: f64 = sources
        .iter()
        .map(|s| {
            0.5 * s.luminance
                * (20.4 * s.solid_angle + 1.52 * libm::pow(s.solid_angle, 0.2) - 0.075)
                / (s.position_index * libm::pow(mean_luminance, 0.44))
        })
        .sum();
    libm::pow(sum, libm::pow(sources.len() as f64, -0.0914))
}

/// Visual comfort probability, the percentage of people who find the
/// view comfortable: 50·erf((6.374 − 1.3227·ln DGR)/√2) + 50; 100 below
/// DGR 20 and 0 above 750, where the fit ends.
pub fn vcp(dgr: f64) -> f64 {
    if dgr < 20.0 {
        100.0
    } else if dgr > 750.0 {
        0.0
    } else {
        50.0 * libm::erf((6.374 - 1.3227 * libm::log(dgr)) / std::f64::consts::SQRT_2) + 50.0
    }
}

#[cfg(test)]
#[allow(clippy::disallowed_methods)]
mod tests {
    use super::*;

    fn towards(sigma_deg: f64, tau_deg: f64) -> [f64; 3] {
        let (s, t) = (sigma_deg.to_radians(), tau_deg.to_radians());
        [
            libm::sin(s) * libm::sin(t),
            libm::sin(s) * libm::cos(t),
            libm::cos(s),
        ]
    }

    #[test]
    fn the_position_index_is_one_ahead_and_grows_off_the_line_of_sight() {
        assert!((position_index([0.0, 0.0, 1.0]) - 1.0).abs() < 1e-12);
        // Above the line of sight, straight up and to the side.
        let mut last = 1.0;
        for sigma in [10.0, 20.0, 40.0, 60.0] {
            let p = position_index(towards(sigma, 90.0));
            assert!(p > last, "σ {sigma}°: {p}");
            last = p;
        }
        // Below the line of sight a source weighs more (P smaller) than the
        // same angle above it.
        assert!(position_index(towards(30.0, 180.0)) < position_index(towards(30.0, 0.0)));
        assert!(position_index(towards(89.0, 90.0)) <= 16.0);
    }

    #[test]
    fn guths_index_matches_the_handbook_fit_by_hand() {
        // σ = 30°, τ = 60° (up and to the side).
        let (s, t): (f64, f64) = (30.0, 60.0);
        let by_hand = ((35.2 - 0.31889 * t - 1.22 * (-2.0 * t / 9.0).exp()) * 1e-3 * s
            + (21.0 + 0.26667 * t - 0.002963 * t * t) * 1e-5 * s * s)
            .exp();
        assert!((position_index(towards(s, t)) - by_hand).abs() < 1e-9);
    }

    #[test]
    fn one_source_ahead_gives_the_indices_of_their_formulas() {
        let source = Seen {
            luminance: 10_000.0,
            solid_angle: 0.01,
            position_index: 1.0,
        };
        let lb = 50.0;
        let ugr_by_hand = 8.0 * (0.25 / lb * 1e8 * 0.01f64).log10();
        assert!((ugr(lb, &[source]) - ugr_by_hand).abs() < 1e-9);
        let ev: f64 = 1000.0;
        let dgp_by_hand = 5.87e-5 * ev + 0.092 * (1.0 + 1e6 / ev.powf(1.87)).log10() + 0.159;
        assert!((dgp(ev, &[source]) - dgp_by_hand).abs() < 1e-12);
        assert_eq!(dgp(1e6, &[source]), 1.0, "DGP is at most 1");
        assert_eq!(vcp(10.0), 100.0);
        assert_eq!(vcp(1000.0), 0.0);
        assert!(vcp(100.0) > 0.0 && vcp(100.0) < 100.0);
    }
}
