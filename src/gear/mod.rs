//! Gear pair: thermal deformation of each gear from its instantaneous radial
//! temperature profile, coating, centre distance, and the normal backlash by the exact
//! involute model, its pitch-averaged closed form and the paper's equations.
//!
//! Convention (`shared/spec/physics.md` §4): the tooth ring moves with the rim, so
//! every tooth dimension of a gear (base tooth thickness, tip radius) scales with that
//! gear's r_b′/r_b; the coating then adds 2K′ to the base tooth thickness.

pub mod backlash;
pub mod check;
pub mod disc;
pub mod involute;
pub mod paper;
pub mod strain;

use backlash::{FlankGeometry, MeshError};
use disc::{BoreFit, DiscMaterial};
use strain::StrainLaw;

/// Most nodes along one gear's radius (checked by the scenario reader).
pub const MAX_GEAR_NODES: usize = 32;

/// One gear of the pair, as built (at the assembly temperature).
#[derive(Debug, Clone, PartialEq)]
pub struct Gear {
    pub name: String,
    pub teeth: u32,
    pub profile_shift: f64,
    pub tip_radius_m: f64,
    pub root_radius_m: f64,
    pub bore_radius_m: f64,
    /// Tooth thickness on the reference circle, uncoated, at the assembly temperature.
    pub tooth_thickness_m: f64,
    pub material: DiscMaterial,
    pub fit: BoreFit,
    /// Network nodes holding the radial profile, bore first, base circle last.
    pub nodes: Vec<usize>,
    /// Their radii (first = bore, last = base circle), m.
    pub node_radii_m: Vec<f64>,
    /// Node of the shaft (elastic fit), if any.
    pub shaft_node: Option<usize>,
}

/// The solid-lubricant film on every flank.
#[derive(Debug, Clone, PartialEq)]
pub struct Coating {
    pub thickness_m: f64,
    pub alpha_per_k: f64,
    pub poisson: f64,
}

impl Coating {
    /// Film thickness when bonded to a substrate with in-plane strain `substrate_strain`
    /// and the film ΔT away from assembly: ε_z = ((1+ν_c) α_c ΔT − 2 ν_c ε_s)/(1 − ν_c).
    pub fn thickness_at_m(&self, delta_t_k: f64, substrate_strain: f64) -> f64 {
        let nu = self.poisson;
        let ez =
            ((1.0 + nu) * self.alpha_per_k * delta_t_k - 2.0 * nu * substrate_strain) / (1.0 - nu);
        self.thickness_m * (1.0 + ez)
    }
}

/// What sets the centre distance.
#[derive(Debug, Clone, PartialEq)]
pub enum CenterDistance {
    /// Fixed at its assembly value (the paper's assumption).
    Fixed,
    /// a′ = a (1 + ε_h(T_h)): follows the housing node's thermal strain.
    Housing { node: usize, strain: StrainLaw },
}

#[derive(Debug, Clone, PartialEq)]
pub struct GearPair {
    pub name: String,
    pub module_m: f64,
    pub pressure_angle_rad: f64,
    pub face_width_m: f64,
    pub center_distance_m: f64,
    pub center: CenterDistance,
    pub reference_temperature_k: f64,
    pub coating: Coating,
    pub min_backlash_m: f64,
    pub gears: [Gear; 2],
    /// What does not change with temperature (base radii and thicknesses at assembly,
    /// the paper model's constants), computed on first use. Pairs are built by
    /// `spec::compile`, and rebuilt on any change, never edited in place.
    pub constants: std::sync::OnceLock<PairConstants>,
    /// Also evaluate the paper's model (eqs. 16–22) at every instant, for reports that
    /// compare it; `margins`, which judges the exact backlash only, switches it off
    /// (the paper's value is then NaN).
    pub paper_model: bool,
}

/// A pair's temperature-independent quantities, each computed by the same expression
/// as where it is used, so caching them changes no bit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairConstants {
    /// Per gear, uncoated at assembly.
    pub base_radius_m: [f64; 2],
    pub base_thickness_m: [f64; 2],
    /// Per gear, the segments of its radial profile (`disc::Segment`).
    pub segments: [[disc::Segment; MAX_GEAR_NODES]; 2],
    pub paper: paper::Constants,
}

/// One gear after deformation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DeformedGear {
    /// Base-circle radial displacement, m.
    pub base_displacement_m: f64,
    pub base_radius_m: f64,
    pub base_pitch_m: f64,
    /// Base tooth thickness with both coatings, m.
    pub base_thickness_m: f64,
    pub tip_radius_m: f64,
    pub coating_m: f64,
    /// Bore contact pressure (elastic fit), Pa; NaN for a rigid bore.
    pub bore_pressure_pa: f64,
}

/// The pair at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MeshState {
    pub gears: [DeformedGear; 2],
    pub center_distance_m: f64,
    pub pressure_angle_rad: f64,
    pub backlash_exact_m: f64,
    pub backlash_closed_form_m: f64,
    pub backlash_paper_m: f64,
    pub contact_ratio: f64,
    /// exact backlash − minimum allowed, m.
    pub margin_m: f64,
}

impl Gear {
    pub fn reference_radius_m(&self, module_m: f64) -> f64 {
        module_m * self.teeth as f64 / 2.0
    }
    pub fn base_radius_m(&self, module_m: f64, alpha0: f64) -> f64 {
        self.reference_radius_m(module_m) * alpha0.cos()
    }
    /// Uncoated base tooth thickness at assembly, m.
    pub fn base_thickness_m(&self, module_m: f64, alpha0: f64) -> f64 {
        involute::base_tooth_thickness(
            self.base_radius_m(module_m, alpha0),
            self.tooth_thickness_m,
            self.reference_radius_m(module_m),
            alpha0,
        )
    }
}

impl GearPair {
    /// The pair's constants (computed on first use).
    pub fn constants(&self) -> &PairConstants {
        self.constants.get_or_init(|| {
            let (m, a0) = (self.module_m, self.pressure_angle_rad);
            PairConstants {
                base_radius_m: [
                    self.gears[0].base_radius_m(m, a0),
                    self.gears[1].base_radius_m(m, a0),
                ],
                base_thickness_m: [
                    self.gears[0].base_thickness_m(m, a0),
                    self.gears[1].base_thickness_m(m, a0),
                ],
                segments: [
                    disc::Segment::of(&self.gears[0].node_radii_m),
                    disc::Segment::of(&self.gears[1].node_radii_m),
                ],
                paper: paper::Constants::of(self),
            }
        })
    }

    /// Gear `k` deformed by its radial profile at node temperatures `temps_k`.
    #[inline(always)]
    fn deform(&self, k: usize, temps_k: &[f64]) -> DeformedGear {
        let t_ref = self.reference_temperature_k;
        let constants = self.constants();
        let mut profile = [0.0f64; MAX_GEAR_NODES];
        let g = &self.gears[k];
        let n = g.nodes.len();
        let temps = &mut profile[..n];
        for (t, &i) in temps.iter_mut().zip(&g.nodes) {
            *t = temps_k[i];
        }
        let shaft_t = g.shaft_node.map_or(t_ref, |i| temps_k[i]);
        let i = disc::strain_moment_with(
            &g.node_radii_m,
            &constants.segments[k][..n - 1],
            temps,
            &g.material.strain,
            t_ref,
        );
        let d =
            disc::displacement_of_moment(&g.node_radii_m, i, &g.material, &g.fit, t_ref, shaft_t);
        let rb0 = constants.base_radius_m[k];
        // The rim's hoop strain u/r at the base-circle node (whose radius may differ
        // from r_b by the rounding of the scenario file).
        let hoop = d.base_circle_m / g.node_radii_m[n - 1];
        let scale = 1.0 + hoop;
        let rim_t = temps[n - 1];
        let coating = self
            .coating
            .thickness_at_m(rim_t - t_ref, g.material.strain.strain(rim_t, t_ref));
        let rb = rb0 * scale;
        DeformedGear {
            base_displacement_m: rb0 * hoop,
            base_radius_m: rb,
            base_pitch_m: std::f64::consts::TAU * rb / g.teeth as f64,
            base_thickness_m: constants.base_thickness_m[k] * scale + 2.0 * coating,
            tip_radius_m: g.tip_radius_m * scale,
            coating_m: coating,
            bore_pressure_pa: d.bore_pressure_pa,
        }
    }

    /// The pair at node temperatures `temps_k` (indexed like the network's nodes).
    pub fn evaluate(&self, temps_k: &[f64]) -> Result<MeshState, MeshError> {
        let (deformed, a) = self.geometry(temps_k);
        let flank = |k: usize| FlankGeometry {
            teeth: self.gears[k].teeth,
            base_radius_m: deformed[k].base_radius_m,
            base_thickness_m: deformed[k].base_thickness_m,
            tip_radius_m: deformed[k].tip_radius_m,
        };
        let b = backlash::backlash(&flank(0), &flank(1), a)?;
        let paper = if self.paper_model {
            paper::backlash_m(self, temps_k, a)
        } else {
            f64::NAN
        };
        Ok(MeshState {
            gears: deformed,
            center_distance_m: a,
            pressure_angle_rad: b.pressure_angle_rad,
            backlash_exact_m: b.exact_m,
            backlash_closed_form_m: b.closed_form_m,
            backlash_paper_m: paper,
            contact_ratio: b.contact_ratio,
            margin_m: b.exact_m - self.min_backlash_m,
        })
    }

    /// The deformed gears and the centre distance at `temps_k`: what [`Self::evaluate`]
    /// meshes, computable whether or not they mesh.
    fn geometry(&self, temps_k: &[f64]) -> ([DeformedGear; 2], f64) {
        let t_ref = self.reference_temperature_k;
        let deformed = [self.deform(0, temps_k), self.deform(1, temps_k)];
        let a = match &self.center {
            CenterDistance::Fixed => self.center_distance_m,
            CenterDistance::Housing { node, strain } => {
                self.center_distance_m * (1.0 + strain.strain(temps_k[*node], t_ref))
            }
        };
        (deformed, a)
    }

    /// [`Self::evaluate`], or when the gears do not mesh, the state with their geometry
    /// (deformed gears, centre distance) and NaN for everything of the mesh (backlash
    /// of every model, margin, pressure angle, contact ratio), with the reason.
    pub fn evaluate_or_invalid(&self, temps_k: &[f64]) -> (MeshState, Option<MeshError>) {
        match self.evaluate(temps_k) {
            Ok(m) => (m, None),
            Err(e) => {
                let (gears, a) = self.geometry(temps_k);
                let state = MeshState {
                    gears,
                    center_distance_m: a,
                    pressure_angle_rad: f64::NAN,
                    backlash_exact_m: f64::NAN,
                    backlash_closed_form_m: f64::NAN,
                    backlash_paper_m: f64::NAN,
                    contact_ratio: f64::NAN,
                    margin_m: f64::NAN,
                };
                (state, Some(e))
            }
        }
    }

    /// Nominal normal backlash at the assembly temperature, m.
    pub fn nominal_backlash_m(&self) -> f64 {
        let m = self.module_m;
        let a0 = self.pressure_angle_rad;
        let g = |k: usize| {
            let gr = &self.gears[k];
            FlankGeometry {
                teeth: gr.teeth,
                base_radius_m: gr.base_radius_m(m, a0),
                base_thickness_m: gr.base_thickness_m(m, a0) + 2.0 * self.coating.thickness_m,
                tip_radius_m: gr.tip_radius_m,
            }
        };
        backlash::backlash(&g(0), &g(1), self.center_distance_m)
            .map(|b| b.exact_m)
            .unwrap_or(f64::NAN)
    }
}
