//! Light transport through the media themselves (pbrt 3rd ed. §15.3): what the `volpath`
//! integrator ([`crate::integrators::volpath`]) is made of, kept apart from the integrator as
//! the probe sampler is from `pathtrace`. No BSSRDF model is used here.
//!
//! - [`interior`]: a translucent material's homogeneous medium in scene units and the
//!   Henyey–Greenstein phase function;
//! - [`boundary`]: the smooth dielectric (Fresnel reflection and refraction, total internal
//!   reflection) and Cycles' Lambertian random-walk boundary;
//! - [`spectral`]: chromatic media, distances sampled in a hero channel with the balance
//!   heuristic over channels (pbrt-v4's bookkeeping);
//! - [`emitters`]: the quad lights and environment a ray leaving the objects reaches;
//! - [`walk`]: one path from a camera hit back to the lights.

pub mod boundary;
pub mod emitters;
pub mod interior;
pub mod spectral;
pub mod walk;
