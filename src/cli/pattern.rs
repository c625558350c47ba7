//! `origami-fmu pattern <kind> [params] -o FILE.fold`: write a generated
//! crease pattern (see [`crate::scene::patterns`]) as a FOLD file.

use super::CliError;
use crate::scene::patterns::{
    CurvedCrease, Kresling, Miura, Pattern, SingleCrease, WaterbombBase, WaterbombTessellation,
    Yoshimura,
};
use clap::{Args, Subcommand};
use std::path::PathBuf;

/// Generate a crease pattern as a FOLD file (lengths in metres, angles in degrees).
#[derive(Args, Debug)]
pub struct PatternArgs {
    #[command(subcommand)]
    kind: Kind,
    /// Output FOLD file (default: standard output).
    #[arg(short, long, global = true, value_name = "FILE")]
    output: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
enum Kind {
    /// Two panels joined by one straight crease.
    SingleCrease {
        /// Width of each panel (m).
        #[arg(long, default_value_t = SingleCrease::default().width)]
        width: f64,
        /// Length of the crease (m).
        #[arg(long, default_value_t = SingleCrease::default().length)]
        length: f64,
        /// Target fold angle (degrees, valley positive).
        #[arg(long, default_value_t = SingleCrease::default().angle, allow_negative_numbers = true)]
        angle: f64,
    },
    /// Miura-ori with rigid-folding targets (Schenk & Guest 2013).
    Miura {
        /// Unit cells along x (the straight crease lines).
        #[arg(long, default_value_t = Miura::default().nx)]
        nx: usize,
        /// Unit cells along y (the zig-zag crease lines).
        #[arg(long, default_value_t = Miura::default().ny)]
        ny: usize,
        /// Facet side along the straight crease lines (m).
        #[arg(long, default_value_t = Miura::default().a)]
        a: f64,
        /// Facet side along the zig-zag crease lines (m).
        #[arg(long, default_value_t = Miura::default().b)]
        b: f64,
        /// Sector angle between the a and b sides (degrees, 0..90).
        #[arg(long, default_value_t = Miura::default().sector_angle)]
        angle: f64,
        /// Fold angle theta of the target state: facets against the sheet plane (degrees, 0..90).
        #[arg(long, default_value_t = Miura::default().fold_angle)]
        fold: f64,
    },
    /// Yoshimura (diamond) pattern; the target closes the strip into a polygonal tube.
    Yoshimura {
        /// Triangles per band (sides of the tube).
        #[arg(long, default_value_t = Yoshimura::default().sides)]
        sides: usize,
        /// Bands of triangles.
        #[arg(long, default_value_t = Yoshimura::default().rows)]
        rows: usize,
        /// Triangle base (m).
        #[arg(long, default_value_t = Yoshimura::default().width)]
        width: f64,
        /// Triangle height (m).
        #[arg(long, default_value_t = Yoshimura::default().height)]
        height: f64,
    },
    /// A single waterbomb base (square with diagonals and midlines), symmetric rigid fold.
    WaterbombBase {
        /// Side of the square (m).
        #[arg(long, default_value_t = WaterbombBase::default().size)]
        size: f64,
        /// Tilt of the corner creases below the sheet plane in the target state (degrees, 0..90).
        #[arg(long, default_value_t = WaterbombBase::default().fold)]
        fold: f64,
    },
    /// Waterbomb (magic-ball) tessellation; targets of the collapsed state.
    Waterbomb {
        /// Bases per band (along x).
        #[arg(long, default_value_t = WaterbombTessellation::default().nx)]
        nx: usize,
        /// Bands (along y).
        #[arg(long, default_value_t = WaterbombTessellation::default().ny)]
        ny: usize,
        /// Side of one base square (m).
        #[arg(long, default_value_t = WaterbombTessellation::default().size)]
        size: f64,
        /// Magnitude of every target (degrees, 180 = flat-folded).
        #[arg(long, default_value_t = WaterbombTessellation::default().fold)]
        fold: f64,
    },
    /// Kresling pattern; the target is the deployed twisted tower.
    Kresling {
        /// Sides of the polygon.
        #[arg(long, default_value_t = Kresling::default().sides)]
        sides: usize,
        /// Stories.
        #[arg(long, default_value_t = Kresling::default().stories)]
        stories: usize,
        /// Polygon side (m).
        #[arg(long, default_value_t = Kresling::default().side)]
        side: f64,
        /// Story height in the deployed state (m).
        #[arg(long, default_value_t = Kresling::default().height)]
        height: f64,
        /// Twist per story in the deployed state (degrees, 0..360/sides).
        #[arg(long, default_value_t = Kresling::default().twist)]
        twist: f64,
    },
    /// A strip with a circular-arc crease cut into short straight creases.
    CurvedCrease {
        /// Strip width across the crease (m).
        #[arg(long, default_value_t = CurvedCrease::default().width)]
        width: f64,
        /// Strip length along the crease (m).
        #[arg(long, default_value_t = CurvedCrease::default().length)]
        length: f64,
        /// Radius of the arc (m).
        #[arg(long, default_value_t = CurvedCrease::default().radius)]
        radius: f64,
        /// Straight crease edges along the arc.
        #[arg(long, default_value_t = CurvedCrease::default().segments)]
        segments: usize,
        /// Target fold angle of every crease edge (degrees, valley positive).
        #[arg(long, default_value_t = CurvedCrease::default().angle, allow_negative_numbers = true)]
        angle: f64,
    },
}

impl Kind {
    fn pattern(&self) -> Pattern {
        match *self {
            Kind::SingleCrease {
                width,
                length,
                angle,
            } => Pattern::SingleCrease(SingleCrease {
                width,
                length,
                angle,
            }),
            Kind::Miura {
                nx,
                ny,
                a,
                b,
                angle,
                fold,
            } => Pattern::Miura(Miura {
                nx,
                ny,
                a,
                b,
                sector_angle: angle,
                fold_angle: fold,
            }),
            Kind::Yoshimura {
                sides,
                rows,
                width,
                height,
            } => Pattern::Yoshimura(Yoshimura {
                sides,
                rows,
                width,
                height,
            }),
            Kind::WaterbombBase { size, fold } => {
                Pattern::WaterbombBase(WaterbombBase { size, fold })
            }
            Kind::Waterbomb { nx, ny, size, fold } => {
                Pattern::Waterbomb(WaterbombTessellation { nx, ny, size, fold })
            }
            Kind::Kresling {
                sides,
                stories,
                side,
                height,
                twist,
            } => Pattern::Kresling(Kresling {
                sides,
                stories,
                side,
                height,
                twist,
            }),
            Kind::CurvedCrease {
                width,
                length,
                radius,
                segments,
                angle,
            } => Pattern::CurvedCrease(CurvedCrease {
                width,
                length,
                radius,
                segments,
                angle,
            }),
        }
    }
}

/// Generate, check that the file loads as a scene, and write it.
pub fn run(args: PatternArgs) -> Result<(), CliError> {
    let file = args.kind.pattern().generate().map_err(CliError::Pattern)?;
    let (scene, _) = crate::scene::from_fold(&file, None).map_err(CliError::PatternDoesNotLoad)?;
    let text = file.to_json();
    let creases = scene.mesh.creases().count();
    let summary = format!(
        "{} vertices, {} edges ({creases} creases), {} faces",
        file.vertices_coords.len(),
        scene.fold_edge_count,
        file.faces_vertices.len()
    );
    match &args.output {
        Some(path) => {
            std::fs::write(path, text).map_err(super::error::io("write", path))?;
            super::err(&format!("wrote {}: {summary}\n", path.display()));
        }
        None => super::out(&text),
    }
    Ok(())
}
