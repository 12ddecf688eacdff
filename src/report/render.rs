//! Pictures of a run: the top view of the height map with hypotheses and detections (the
//! paper's Fig. 4 b-d in one image) and orthographic views of the cloud with the posed
//! agents, written as PNG.
//!
//! Image frame: pixel `(0, 0)` is the top-left corner, x grows to the right and y down;
//! RGB, 8 bits per channel. World frame: metres, z up.

use std::path::Path;

use nalgebra::{Point2, Point3, Vector3};

use crate::cloud::PointCloud;
use crate::detect::{Detection, Outcome, Prepared};
use crate::method::heightmap::HeightMap;
use crate::method::holes::Hole;
use crate::method::hypotheses::Hypothesis;
use crate::model::hierarchy::Hierarchy;
use crate::num::{to_i64, to_usize};

/// An RGB image, 8 bits per channel, row-major from the top-left corner.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `3 * width * height` bytes, `r, g, b` per pixel, rows from the top.
    pub rgb: Vec<u8>,
}

/// Colour of a detection with affordances that are none of its [`Legend`]'s.
pub const OTHER_AFFORDANCE: [u8; 3] = [160, 160, 160];

/// Colour of hypothesis arrows (Fig. 4c).
pub const HYPOTHESIS_COLOUR: [u8; 3] = [230, 20, 20];

const BACKGROUND: [u8; 3] = [255, 255, 255];
const INVALID_CELL: [u8; 3] = [28, 28, 32];
/// Hatching over height-map cells filled where the scan saw nothing.
pub const FILL_HATCH: [u8; 3] = [235, 235, 235];
const INK: [u8; 3] = [20, 20, 20];
/// Height of the legend strip under the height map, pixels.
pub const LEGEND_HEIGHT: u32 = 46;
/// Smallest width of a height-map image, so that its legend fits, pixels.
pub const LEGEND_MIN_WIDTH: u32 = 280;
/// Radius of the seat circle of a detection, metres.
const SEAT_RADIUS: f64 = 0.10;
/// Length of the heading arrow of a detection, metres.
const HEADING_LENGTH: f64 = 0.30;

/// How detections are coloured: affordance ids with their sRGB colours, coarsest first,
/// gathered from the legends of the hierarchies in use ([`Hierarchy::legend`]), so a new
/// hierarchy draws in its own colours.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Legend {
    entries: Vec<(String, [u8; 3])>,
}

impl Legend {
    /// The legend of `entries` (id and colour, coarsest first).
    pub fn new(entries: Vec<(String, [u8; 3])>) -> Legend {
        Legend { entries }
    }

    /// The legends of `hierarchies` one after the other; an id already listed keeps its
    /// first colour.
    pub fn of<'a>(hierarchies: impl IntoIterator<Item = &'a Hierarchy>) -> Legend {
        let mut entries: Vec<(String, [u8; 3])> = Vec::new();
        for (id, c) in hierarchies.into_iter().flat_map(|h| &h.legend) {
            if !entries.iter().any(|(e, _)| e == id) {
                entries.push((id.clone(), *c));
            }
        }
        Legend { entries }
    }

    /// The ids and colours, coarsest first.
    pub fn entries(&self) -> &[(String, [u8; 3])] {
        &self.entries
    }

    /// The finest affordance in `affordances` (ids of one detection, in hierarchy order):
    /// the one latest in the legend (for the built-in hierarchies, headrest over armrest
    /// over backrest over sitting; raised body over raised legs over lying flat), else the
    /// last one; `None` for none.
    pub fn finest<'a>(&self, affordances: &'a [String]) -> Option<&'a str> {
        self.entries
            .iter()
            .rev()
            .find_map(|(id, _)| affordances.iter().find(|a| *a == id))
            .or(affordances.last())
            .map(String::as_str)
    }

    /// The colour of the finest affordance in `affordances` ([`Self::finest`]);
    /// [`OTHER_AFFORDANCE`] if it is not in the legend.
    pub fn colour(&self, affordances: &[String]) -> [u8; 3] {
        let finest = self.finest(affordances);
        self.entries
            .iter()
            .find(|(id, _)| Some(id.as_str()) == finest)
            .map_or(OTHER_AFFORDANCE, |(_, c)| *c)
    }
}

/// Viridis, approximated by 9 stops; `t` in `0..=1` (clamped), dark purple to yellow.
pub fn viridis(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [71.0, 44.0, 122.0],
        [59.0, 81.0, 139.0],
        [44.0, 113.0, 142.0],
        [33.0, 144.0, 141.0],
        [39.0, 173.0, 129.0],
        [92.0, 200.0, 99.0],
        [170.0, 220.0, 50.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let i = to_usize(x.floor()).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for (k, v) in c.iter_mut().enumerate() {
        *v = channel(STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f);
    }
    c
}

/// A colour channel from a value on the 0-255 scale: rounded and clamped, which is what
/// `as` does (it saturates) made explicit.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn channel(v: f64) -> u8 {
    // Clamped to 0..=255 first: the cast drops nothing.
    v.round().clamp(0.0, 255.0) as u8
}

/// A pixel coordinate already checked to lie in the image (so at least 0), as an index.
fn ix(v: i64) -> usize {
    usize::try_from(v).unwrap_or(0)
}

/// A size in pixels (cells of a height map, images of a panel), saturating: the extent
/// guard keeps a height map under 90 million cells, far below `u32::MAX`.
fn px(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

fn scale_colour(c: [u8; 3], f: f64) -> [u8; 3] {
    c.map(|v| channel(v as f64 * f))
}

fn mix(a: [u8; 3], b: [u8; 3], t: f64) -> [u8; 3] {
    let t = t.clamp(0.0, 1.0);
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = channel(a[k] as f64 * (1.0 - t) + b[k] as f64 * t);
    }
    c
}

/// Distance from `p` to the segment `a`-`b` and the segment parameter `t` in `0..=1`.
fn segment_distance(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>) -> (f64, f64) {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 1e-12 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p - (a + ab * t)).norm(), t)
}

impl Image {
    /// A `width` x `height` image filled with `colour`.
    pub fn new(width: u32, height: u32, colour: [u8; 3]) -> Image {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&colour);
        }
        Image { width, height, rgb }
    }

    /// The colour of pixel `(x, y)` (from the top-left corner); panics outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(x < self.width && y < self.height, "pixel outside the image");
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Sets pixel `(x, y)`; ignored outside the image.
    pub fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        self.blend(x, y, c, 1.0);
    }

    /// Blends `c` over pixel `(x, y)` with opacity `alpha` (0..1); ignored outside.
    pub fn blend(&mut self, x: i64, y: i64, c: [u8; 3], alpha: f64) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 || alpha <= 0.0 {
            return;
        }
        let i = 3 * (ix(y) * self.width as usize + ix(x));
        let old = [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]];
        let new = mix(old, c, alpha);
        self.rgb[i..i + 3].copy_from_slice(&new);
    }

    /// Fills the rectangle `[x, x + w) x [y, y + h)` (pixels), clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: [u8; 3]) {
        for yy in y.max(0)..(y + h).min(self.height as i64) {
            for xx in x.max(0)..(x + w).min(self.width as i64) {
                self.set(xx, yy, c);
            }
        }
    }

    /// Visits the pixels within `pad` of the box spanned by `pts` (pixel coordinates),
    /// with each pixel's centre.
    fn for_box(
        &mut self,
        pts: &[Point2<f64>],
        pad: f64,
        mut f: impl FnMut(&mut Image, i64, i64, Point2<f64>),
    ) {
        let (mut lo, mut hi) = (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        );
        for p in pts {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if !(lo.x.is_finite() && hi.x.is_finite() && lo.y.is_finite() && hi.y.is_finite()) {
            return;
        }
        let x0 = to_i64((lo.x - pad).floor()).max(0);
        let y0 = to_i64((lo.y - pad).floor()).max(0);
        let x1 = to_i64((hi.x + pad).ceil()).min(self.width as i64 - 1);
        let y1 = to_i64((hi.y + pad).ceil()).min(self.height as i64 - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                f(self, x, y, Point2::new(x as f64 + 0.5, y as f64 + 0.5));
            }
        }
    }

    /// An antialiased thick line with round ends (a capsule) of half-width `r` pixels
    /// from `a` to `b` (pixel coordinates), opacity `alpha`.
    pub fn line(&mut self, a: Point2<f64>, b: Point2<f64>, r: f64, c: [u8; 3], alpha: f64) {
        self.for_box(&[a, b], r + 1.0, |img, x, y, p| {
            let (d, _) = segment_distance(p, a, b);
            img.blend(x, y, c, alpha * (r + 0.5 - d).clamp(0.0, 1.0));
        });
    }

    /// A filled antialiased disc of radius `r` pixels.
    pub fn disc(&mut self, centre: Point2<f64>, r: f64, c: [u8; 3]) {
        self.line(centre, centre, r, c, 1.0);
    }

    /// An antialiased circle of radius `r` and line half-width `w` pixels.
    pub fn ring(&mut self, centre: Point2<f64>, r: f64, w: f64, c: [u8; 3]) {
        self.for_box(&[centre], r + w + 1.0, |img, x, y, p| {
            let d = ((p - centre).norm() - r).abs();
            img.blend(x, y, c, (w + 0.5 - d).clamp(0.0, 1.0));
        });
    }

    /// An arrow from `a` to `b` (pixels) of half-width `r`, head a quarter of its length
    /// (at least 2 px).
    pub fn arrow(&mut self, a: Point2<f64>, b: Point2<f64>, r: f64, c: [u8; 3]) {
        self.line(a, b, r, c, 1.0);
        let d = b - a;
        let len = d.norm();
        if len < 1e-9 {
            return;
        }
        let head = (len * 0.4).max(2.0);
        let u = d / len;
        for s in [-1.0, 1.0] {
            let (sn, cs) = (s * 2.6_f64).sin_cos();
            let v = nalgebra::Vector2::new(u.x * cs - u.y * sn, u.x * sn + u.y * cs);
            self.line(b, b + v * head, r, c, 1.0);
        }
    }

    /// Writes `text` with the built-in 5x7 font, top-left corner at `(x, y)`, each font
    /// pixel `size` x `size` pixels; characters without a glyph are left blank.
    /// Returns the x just after the text.
    pub fn text(&mut self, x: i64, y: i64, text: &str, size: i64, c: [u8; 3]) -> i64 {
        let mut cx = x;
        for ch in text.chars() {
            if let Some(rows) = glyph(ch) {
                for (ry, row) in rows.iter().enumerate() {
                    for rx in 0..5 {
                        if row & (0x10 >> rx) != 0 {
                            self.fill_rect(cx + rx * size, y + ry as i64 * size, size, size, c);
                        }
                    }
                }
            }
            cx += 6 * size;
        }
        cx
    }

    /// Encodes the image as PNG (8-bit RGB).
    pub fn png_bytes(&self) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(std::io::Error::other)?;
            w.write_image_data(&self.rgb)
                .map_err(std::io::Error::other)?;
            w.finish().map_err(std::io::Error::other)?;
        }
        Ok(out)
    }

    /// Saves the image as PNG at `path`, atomically: a temporary file in the same
    /// directory is written, synced and renamed into place.
    pub fn save_png(&self, path: &Path) -> std::io::Result<()> {
        crate::report::atomic::write_bytes(path, &self.png_bytes()?)
    }
}

/// 5x7 glyphs: 7 rows, bit 4 the leftmost column.
fn glyph(c: char) -> Option<[u8; 7]> {
    Some(match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        ' ' => [0; 7],
        'a' => [0, 0, 0x0E, 0x01, 0x0F, 0x11, 0x0F],
        'b' => [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E],
        'c' => [0, 0, 0x0E, 0x10, 0x10, 0x11, 0x0E],
        'd' => [0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F],
        'e' => [0, 0, 0x0E, 0x11, 0x1F, 0x10, 0x0E],
        'f' => [0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08],
        'g' => [0, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E],
        'h' => [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11],
        'i' => [0x04, 0, 0x0C, 0x04, 0x04, 0x04, 0x0E],
        'k' => [0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12],
        'l' => [0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'm' => [0, 0, 0x1A, 0x15, 0x15, 0x11, 0x11],
        'n' => [0, 0, 0x16, 0x19, 0x11, 0x11, 0x11],
        'o' => [0, 0, 0x0E, 0x11, 0x11, 0x11, 0x0E],
        'p' => [0, 0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10],
        'r' => [0, 0, 0x16, 0x19, 0x10, 0x10, 0x10],
        's' => [0, 0, 0x0E, 0x10, 0x0E, 0x01, 0x1E],
        't' => [0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06],
        'u' => [0, 0, 0x11, 0x11, 0x11, 0x13, 0x0D],
        'v' => [0, 0, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'w' => [0, 0, 0x11, 0x11, 0x15, 0x15, 0x0A],
        'x' => [0, 0, 0x11, 0x0A, 0x04, 0x0A, 0x11],
        'y' => [0, 0x11, 0x11, 0x11, 0x0F, 0x01, 0x0E],
        'z' => [0, 0, 0x1F, 0x02, 0x04, 0x08, 0x1F],
        _ => return None,
    })
}

/// The top view of the paper's Fig. 4 b-d in one image.
///
/// Every height-map cell is a `scale` x `scale` pixel block coloured by its height
/// ([`viridis`] from the lowest to the highest valid cell; invalid cells near black);
/// world x points to the right and world y up, cell `(ix, iy)` covering pixels
/// `ix * scale ..` horizontally and `(ny - 1 - iy) * scale ..` vertically. Hypotheses
/// are red arrows from their cell centre along their heading, of length `availability`
/// times 1.5 cells (a dot for no heading). Each detection shows the top-view silhouette
/// of its posed body parts, a circle around its seat and a heading arrow, in the colour
/// of its finest affordance ([`Legend::colour`]).
///
/// The cells of `filled` (holes the scan did not see, filled at the level round them:
/// [`crate::method::holes`]) are hatched with [`FILL_HATCH`].
///
/// The image is `max(nx * scale, LEGEND_MIN_WIDTH)` wide and `ny * scale +
/// LEGEND_HEIGHT` tall: a legend strip (height range, affordance colours) is at the bottom.
pub fn heightmap_image(
    map: &HeightMap,
    filled: &[Hole],
    hyps: &[Hypothesis],
    detections: &[Detection],
    legend: &Legend,
    scale: u32,
) -> Image {
    let scale = scale.max(1);
    let (mw, mh) = (px(map.nx) * scale, px(map.ny) * scale);
    let mut img = Image::new(mw.max(LEGEND_MIN_WIDTH), mh + LEGEND_HEIGHT, BACKGROUND);
    let (lo, hi) = map
        .valid_heights()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), z| {
            (l.min(z), h.max(z))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    for iy in 0..map.ny {
        for ix in 0..map.nx {
            let c = map
                .get(ix as isize, iy as isize)
                .map_or(INVALID_CELL, |z| viridis((z - lo) / span));
            let py = (map.ny - 1 - iy) as i64 * scale as i64;
            img.fill_rect(ix as i64 * scale as i64, py, scale as i64, scale as i64, c);
        }
    }
    for &(ix, iy) in filled.iter().flat_map(|h| &h.cells) {
        let (x0, y0) = (
            ix as i64 * scale as i64,
            (map.ny - 1 - iy) as i64 * scale as i64,
        );
        hatch(&mut img, x0, y0, scale as i64);
    }
    let s = scale as f64;
    let to_px = |x: f64, y: f64| {
        Point2::new(
            (x - map.x0) / map.cell * s,
            (map.ny as f64 - (y - map.y0) / map.cell) * s,
        )
    };
    let px_per_m = s / map.cell;
    let thin = (s / 16.0).max(0.5);
    for d in detections {
        let col = legend.colour(&d.affordances);
        let segs: Vec<(Point2<f64>, Point2<f64>, f64)> = d
            .parts
            .iter()
            .map(|c| {
                (
                    to_px(c.a.x, c.a.y),
                    to_px(c.b.x, c.b.y),
                    c.radius * px_per_m,
                )
            })
            .collect();
        let pts: Vec<Point2<f64>> = segs.iter().flat_map(|s| [s.0, s.1]).collect();
        let pad = segs.iter().map(|s| s.2).fold(0.0, f64::max) + 2.0;
        img.for_box(&pts, pad, |img, x, y, p| {
            let sdf = segs
                .iter()
                .map(|(a, b, r)| segment_distance(p, *a, *b).0 - r)
                .fold(f64::INFINITY, f64::min);
            // Fill inside, dark outline on the silhouette's edge.
            img.blend(x, y, col, 0.35 * (0.5 - sdf).clamp(0.0, 1.0));
            img.blend(x, y, INK, (1.0 - (sdf + 0.25).abs()).clamp(0.0, 1.0));
        });
    }
    for h in hyps {
        let c = to_px(h.position.x, h.position.y);
        match h.heading {
            Some(a) => {
                let len = h.availability.clamp(0.0, 1.0) * 1.8 * s;
                // Image y grows downwards: world +y is -y in pixels.
                let tip = c + nalgebra::Vector2::new(a.cos(), -a.sin()) * len;
                img.arrow(c, tip, thin + 0.8, INK);
                img.arrow(c, tip, thin, HYPOTHESIS_COLOUR);
            }
            None => img.disc(
                c,
                (h.availability.clamp(0.0, 1.0) * 0.25 * s).max(1.0),
                HYPOTHESIS_COLOUR,
            ),
        }
    }
    for (i, d) in detections.iter().enumerate() {
        let col = legend.colour(&d.affordances);
        let seat = to_px(d.seat.x, d.seat.y);
        let tip =
            seat + nalgebra::Vector2::new(d.yaw.cos(), -d.yaw.sin()) * HEADING_LENGTH * px_per_m;
        let w = (s / 8.0).max(1.0);
        img.ring(seat, SEAT_RADIUS * px_per_m, w + 1.0, INK);
        img.arrow(seat, tip, w + 1.0, INK);
        img.ring(seat, SEAT_RADIUS * px_per_m, w, col);
        img.arrow(seat, tip, w, col);
        img.disc(seat, w + 1.5, col);
        // The detection's index (as in the reports), beside the seat circle, opposite the arrow.
        let label = format!("{i}");
        let at = seat
            - nalgebra::Vector2::new(d.yaw.cos(), -d.yaw.sin()) * (SEAT_RADIUS * px_per_m + 10.0);
        let (lx, ly) = (to_i64(at.x) - 5 * label.len() as i64, to_i64(at.y) - 7);
        for (dx, dy) in [
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, 1),
            (-1, 1),
            (1, -1),
        ] {
            img.text(lx + dx, ly + dy, &label, 2, INK);
        }
        img.text(lx, ly, &label, 2, [255; 3]);
    }
    draw_legend(&mut img, mh as i64, (lo, hi), !filled.is_empty(), legend);
    img
}

/// Hatches the `size` x `size` block at `(x0, y0)`: every pixel on every fourth diagonal.
fn hatch(img: &mut Image, x0: i64, y0: i64, size: i64) {
    for y in y0..y0 + size {
        for x in x0..x0 + size {
            if (x + y) % 4 == 0 {
                img.set(x, y, FILL_HATCH);
            }
        }
    }
}

fn draw_legend(img: &mut Image, top: i64, (lo, hi): (f64, f64), filled: bool, legend: &Legend) {
    let y = top + 4;
    let mut x = 4;
    if lo.is_finite() {
        x = img.text(x, y, &format!("z {lo:.2}"), 1, INK) + 2;
        for i in 0..80 {
            img.fill_rect(x + i, y - 1, 1, 9, viridis(i as f64 / 79.0));
        }
        x = img.text(x + 84, y, &format!("{hi:.2} m"), 1, INK) + 8;
    }
    img.arrow(
        Point2::new(x as f64, y as f64 + 3.5),
        Point2::new(x as f64 + 12.0, y as f64 + 3.5),
        0.6,
        HYPOTHESIS_COLOUR,
    );
    let x = img.text(x + 16, y, "hypothesis", 1, INK) + 8;
    if filled {
        img.fill_rect(x, y - 1, 9, 9, viridis(0.5));
        hatch(img, x, y - 1, 9);
        img.text(x + 12, y, "unseen - filled", 1, INK);
    }
    let mut y = top + 20;
    let mut x = 4;
    for (id, c) in legend.entries() {
        let c = *c;
        // Wrap to a second row when the entry (box and ~6 px per letter) would not fit.
        if x + 12 + 6 * id.len() as i64 > i64::from(img.width) {
            x = 4;
            y += 12;
        }
        img.fill_rect(x, y - 1, 9, 9, INK);
        img.fill_rect(x + 1, y, 7, 7, c);
        x = img.text(x + 12, y, id, 1, INK) + 6;
    }
}

/// A direction to look at the scene from (orthographic).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    /// From above: world x to the right, y up.
    Top,
    /// From +x towards -x (the front of synthetic furniture): world y to the right, z up.
    Front,
    /// From -y towards +y: world x to the right, z up.
    Side,
    /// From the front-left and above (+x, -y, +z), isometric-like.
    Iso,
}

impl View {
    /// Name drawn in the corner of the picture.
    pub fn name(self) -> &'static str {
        match self {
            View::Top => "top",
            View::Front => "front",
            View::Side => "side",
            View::Iso => "iso",
        }
    }

    /// Camera basis `(right, up, towards the viewer)`, orthonormal, world frame.
    pub fn basis(self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let back = match self {
            View::Top => return (Vector3::x(), Vector3::y(), Vector3::z()),
            View::Front => Vector3::x(),
            View::Side => -Vector3::y(),
            View::Iso => Vector3::new(1.0, -0.9, 0.85).normalize(),
        };
        let right = Vector3::z().cross(&back).normalize();
        let up = back.cross(&right);
        (right, up, back)
    }
}

/// An orthographic picture of `cloud` (points coloured by height, darker when further)
/// seen from `view`, with the posed body parts of `detections` drawn as shaded capsules in
/// the colour of their finest affordance; points and parts share a z-buffer, so whichever
/// is nearer to the viewer shows. The view is fitted to the bounds of the cloud and the
/// parts with a margin; metres map to pixels equally along both axes. `width` x `height`
/// pixels, white background.
pub fn scene_image(
    cloud: &PointCloud,
    detections: &[Detection],
    legend: &Legend,
    view: View,
    width: u32,
    height: u32,
) -> Image {
    let (width, height) = (width.max(1), height.max(1));
    let mut img = Image::new(width, height, BACKGROUND);
    let (right, up, back) = view.basis();
    let proj = |p: &Point3<f64>| (p.coords.dot(&right), p.coords.dot(&up), p.coords.dot(&back));
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut grow = |q: (f64, f64, f64), r: f64| {
        for (k, v) in [q.0, q.1, q.2].into_iter().enumerate() {
            lo[k] = lo[k].min(v - r);
            hi[k] = hi[k].max(v + r);
        }
    };
    for p in &cloud.points {
        grow(proj(p), 0.0);
    }
    for c in detections.iter().flat_map(|d| &d.parts) {
        grow(proj(&c.a), c.radius);
        grow(proj(&c.b), c.radius);
    }
    if !lo[0].is_finite() {
        img.text(6, 6, view.name(), 2, INK);
        return img;
    }
    let margin = 10.0 + 0.04 * width.min(height) as f64;
    let (sw, sh) = ((hi[0] - lo[0]).max(1e-6), (hi[1] - lo[1]).max(1e-6));
    let k = ((width as f64 - 2.0 * margin) / sw)
        .min((height as f64 - 2.0 * margin) / sh)
        .max(1e-6);
    let (cx, cy) = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0);
    let to_px = |s: f64, t: f64| {
        Point2::new(
            width as f64 / 2.0 + (s - cx) * k,
            height as f64 / 2.0 - (t - cy) * k,
        )
    };
    let (zlo, zhi) = cloud
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.z), h.max(p.z))
        });
    let zspan = if zhi > zlo { zhi - zlo } else { 1.0 };
    let dspan = (hi[2] - lo[2]).max(1e-6);
    let mut zbuf = vec![f64::NEG_INFINITY; width as usize * height as usize];
    // Splats of about 1 cm, 1 to 3 pixels.
    let splat = to_i64((0.008 * k).round()).clamp(1, 3);
    for p in &cloud.points {
        let (s, t, depth) = proj(p);
        let q = to_px(s, t);
        let fog = 0.6 + 0.4 * (depth - lo[2]) / dspan;
        let c = scale_colour(mix(viridis((p.z - zlo) / zspan), [255; 3], 0.15), fog);
        let (x0, y0) = (
            to_i64((q.x - splat as f64 / 2.0).round()),
            to_i64((q.y - splat as f64 / 2.0).round()),
        );
        for y in y0..y0 + splat {
            for x in x0..x0 + splat {
                if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
                    continue;
                }
                let i = ix(y) * width as usize + ix(x);
                if depth > zbuf[i] {
                    zbuf[i] = depth;
                    img.set(x, y, c);
                }
            }
        }
    }
    // Light from the upper left, towards the scene, in camera coordinates (right, up, back).
    let light = Vector3::new(-0.45, 0.55, 0.7).normalize();
    for d in detections {
        let col = legend.colour(&d.affordances);
        for c in &d.parts {
            let (sa, ta, da) = proj(&c.a);
            let (sb, tb, db) = proj(&c.b);
            let (a, b) = (to_px(sa, ta), to_px(sb, tb));
            let r = (c.radius * k).max(0.8);
            let axis = b - a;
            let across = if axis.norm() > 1e-9 {
                nalgebra::Vector2::new(-axis.y, axis.x).normalize()
            } else {
                nalgebra::Vector2::new(1.0, 0.0)
            };
            img.for_box(&[a, b], r + 1.0, |img, x, y, p| {
                let (dist, t) = segment_distance(p, a, b);
                if dist > r + 0.5 {
                    return;
                }
                let i = ix(y) * width as usize + ix(x);
                let h = (1.0 - (dist / r).min(1.0).powi(2)).sqrt();
                let depth = da + (db - da) * t + h * c.radius;
                if depth <= zbuf[i] {
                    return;
                }
                // Surface normal in camera coordinates (image y points down).
                let off = p - (a + axis * t);
                let side = if off.norm() > 1e-9 {
                    off / r
                } else {
                    across * 0.0
                };
                let n = Vector3::new(side.x, -side.y, h);
                let lambert = n.normalize().dot(&light).max(0.0);
                let shade = 0.35 + 0.75 * lambert;
                let mut shaded = scale_colour(col, shade);
                let edge = (dist - (r - 1.0)).clamp(0.0, 1.0);
                shaded = mix(shaded, scale_colour(col, 0.3), edge);
                let alpha = (r + 0.5 - dist).clamp(0.0, 1.0);
                zbuf[i] = depth;
                img.blend(x, y, shaded, alpha);
            });
        }
    }
    img.text(6, 6, view.name(), 2, INK);
    img
}

/// The images side by side, tops aligned, separated by 6 white pixels, the shorter ones
/// padded with white at the bottom.
pub fn panel(images: &[Image]) -> Image {
    const GAP: u32 = 6;
    let width =
        images.iter().map(|i| i.width).sum::<u32>() + GAP * px(images.len().saturating_sub(1));
    let height = images.iter().map(|i| i.height).max().unwrap_or(0);
    let mut out = Image::new(width, height, BACKGROUND);
    let mut x0 = 0usize;
    for im in images {
        for y in 0..im.height as usize {
            let src = &im.rgb[3 * y * im.width as usize..3 * (y + 1) * im.width as usize];
            let start = 3 * (y * width as usize + x0);
            out.rgb[start..start + src.len()].copy_from_slice(src);
        }
        x0 += (im.width + GAP) as usize;
    }
    out
}

/// The cell size in pixels that makes a height map of `nx` x `ny` cells about `target`
/// pixels on its longer side (1 to 16).
pub fn auto_scale(nx: usize, ny: usize, target: u32) -> u32 {
    let n = px(nx.max(ny).max(1));
    (target / n).clamp(1, 16)
}

/// Saves at `path` (PNG, atomically) the panel `afford inspect --png` shows: the height
/// map with `hyps` and the detections of `outcome` ([`heightmap_image`], about 480 pixels
/// on its longer side) and the cloud with the posed agents from the [`View::Iso`] and
/// [`View::Side`] directions ([`scene_image`]), all of the same height.
pub fn inspect_png(
    cloud: &PointCloud,
    prepared: &Prepared,
    hyps: &[Hypothesis],
    outcome: &Outcome,
    legend: &Legend,
    path: &Path,
) -> std::io::Result<()> {
    let map = &prepared.map;
    let top = heightmap_image(
        map,
        &prepared.filled,
        hyps,
        &outcome.detections,
        legend,
        auto_scale(map.nx, map.ny, 480),
    );
    let h = top.height.max(360);
    let iso = scene_image(cloud, &outcome.detections, legend, View::Iso, h, h);
    let side = scene_image(cloud, &outcome.detections, legend, View::Side, h, h);
    panel(&[top, iso, side]).save_png(path)
}

/// The legend of the built-in hierarchies (sitting, then lying) for the built-in human.
#[cfg(test)]
pub(crate) fn builtin_legend() -> Legend {
    use crate::model::set::{load_set, sources, BUILTIN_AGENTS, BUILTIN_HIERARCHIES};
    let agents = sources(&[], BUILTIN_AGENTS, &["human"]).unwrap();
    let hierarchies = sources(&[], BUILTIN_HIERARCHIES, &["sitting", "lying"]).unwrap();
    let models = load_set(&agents, &hierarchies, &[1.75]).unwrap();
    Legend::of(models.iter().map(|m| &m.hierarchy))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::agent::Cylinder;

    fn map_3x2() -> HeightMap {
        // Row 0 (bottom): 0.0, 0.5, invalid; row 1 (top): 1.0, 0.2, 0.0.
        HeightMap::from_dense(
            0.0,
            0.0,
            0.1,
            3,
            2,
            &[Some(0.0), Some(0.5), None, Some(1.0), Some(0.2), Some(0.0)],
        )
    }

    fn detection(affordances: &[&str], parts: Vec<Cylinder>) -> Detection {
        Detection {
            agent: "human".into(),
            height: 1.75,
            hierarchy: "sitting".into(),
            position: Point3::new(0.0, 0.0, 0.5),
            yaw: 0.0,
            seat: Point3::new(0.0, 0.0, 0.45),
            affordances: affordances.iter().map(|s| s.to_string()).collect(),
            local_scores: vec![],
            pose: vec![],
            score: 1.0,
            stability: 1.0,
            availability: 1.0,
            segment_points: 0,
            parts,
            joints: vec![],
        }
    }

    fn hyp(cell: (usize, usize), map: &HeightMap, heading: Option<f64>) -> Hypothesis {
        let (x, y) = map.centre(cell.0, cell.1);
        Hypothesis {
            cell,
            position: Point3::new(x, y, 0.5),
            top: 0.5,
            availability: 1.0,
            heading,
            facing: None,
            memberships: [1.0; 3],
            risen: false,
            unseen_width: false,
            flat_axes: Vec::new(),
        }
    }

    #[test]
    fn heightmap_image_size_colours_and_orientation() {
        let m = map_3x2();
        let img = heightmap_image(&m, &[], &[], &[], &Legend::default(), 10);
        assert_eq!(img.width, LEGEND_MIN_WIDTH);
        assert_eq!(img.height, 20 + LEGEND_HEIGHT);
        assert_eq!(img.rgb.len(), 3 * (img.width * img.height) as usize);
        // World y up: row 1 (the highest cell at ix 0) is the top row of pixels.
        assert_eq!(img.pixel(5, 5), viridis(1.0));
        assert_eq!(img.pixel(5, 15), viridis(0.0));
        assert_eq!(img.pixel(15, 15), viridis(0.5));
        // The invalid cell (2, 0) is dark.
        let c = img.pixel(25, 15);
        assert!(c.iter().all(|&v| v < 40), "{c:?}");
        // High end of the map is yellow, low end purple.
        assert!(viridis(1.0)[0] > 200 && viridis(1.0)[1] > 200 && viridis(1.0)[2] < 80);
        assert!(viridis(0.0)[2] > viridis(0.0)[1]);
        // A wide map is as wide as its cells.
        let wide = HeightMap::from_dense(m.x0, m.y0, m.cell, 40, m.ny, &[Some(0.3); 80]);
        assert_eq!(
            heightmap_image(&wide, &[], &[], &[], &Legend::default(), 8).width,
            320
        );
    }

    #[test]
    fn filled_cells_are_hatched_and_named_in_the_legend() {
        let m = HeightMap::from_dense(0.0, 0.0, 0.1, 4, 2, &[Some(0.5); 8]);
        let hole = Hole {
            cells: vec![(1, 0)],
            height: 0.5,
        };
        let plain = heightmap_image(&m, &[], &[], &[], &Legend::default(), 10);
        let img = heightmap_image(&m, &[hole], &[], &[], &Legend::default(), 10);
        // Cell (1, 0) covers pixels x 10-19, y 10-19: hatched on its diagonals (x + y a
        // multiple of 4), its colour between them; cell (2, 0) as without the fill.
        assert_eq!(img.pixel(12, 12), FILL_HATCH);
        assert_eq!(img.pixel(13, 12), plain.pixel(13, 12));
        assert_eq!(img.pixel(24, 12), plain.pixel(24, 12));
        assert_ne!(plain.pixel(12, 12), FILL_HATCH);
        // The legend names the hatching only when something was filled.
        let legend_row = |i: &Image| {
            (0..i.width)
                .map(|x| i.pixel(x, 20 + 4 + 3))
                .collect::<Vec<_>>()
        };
        assert_ne!(legend_row(&img), legend_row(&plain));
    }

    fn is_red(c: [u8; 3]) -> bool {
        c[0] > 150 && c[1] < 90 && c[2] < 90
    }

    #[test]
    fn hypothesis_arrows_point_along_the_heading() {
        let m = HeightMap::from_dense(0.0, 0.0, 0.1, 9, 9, &[Some(0.0); 81]);
        // Heading 0 (+x): red to the right of the centre (45, 45), not to the left.
        let img = heightmap_image(
            &m,
            &[],
            &[hyp((4, 4), &m, Some(0.0))],
            &[],
            &Legend::default(),
            10,
        );
        assert!(is_red(img.pixel(52, 44)), "{:?}", img.pixel(52, 44));
        assert!(!is_red(img.pixel(38, 44)));
        // Heading +90 deg (+y): red above the centre in the image.
        let img = heightmap_image(
            &m,
            &[],
            &[hyp((4, 4), &m, Some(std::f64::consts::FRAC_PI_2))],
            &[],
            &Legend::default(),
            10,
        );
        assert!(is_red(img.pixel(44, 37)) || is_red(img.pixel(45, 37)));
        assert!(!is_red(img.pixel(45, 53)));
        // No heading: a dot on the centre.
        let img = heightmap_image(
            &m,
            &[],
            &[hyp((4, 4), &m, None)],
            &[],
            &Legend::default(),
            10,
        );
        assert!(is_red(img.pixel(45, 45)));
        assert!(!is_red(img.pixel(52, 45)));
    }

    #[test]
    fn detection_drawn_in_its_finest_affordance_colour() {
        let strs = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let legend = builtin_legend();
        let colour = |id: &str| {
            legend
                .entries()
                .iter()
                .find(|(e, _)| e == id)
                .map(|(_, c)| *c)
                .unwrap()
        };
        let drawn = |a: &[&str]| legend.colour(&strs(a));
        assert_eq!(drawn(&["sitting"]), colour("sitting"));
        assert_eq!(
            drawn(&["sitting", "backrest", "headrest"]),
            colour("headrest")
        );
        assert_eq!(
            drawn(&["sitting", "armrest", "backrest"]),
            colour("armrest")
        );
        assert_eq!(
            drawn(&["lying", "elongated_body", "stretched_legs"]),
            colour("lying")
        );
        assert_eq!(
            drawn(&["lying", "raised_body", "raised_legs"]),
            colour("raised_body")
        );
        assert_eq!(drawn(&["perching"]), OTHER_AFFORDANCE);
        assert_eq!(drawn(&[]), OTHER_AFFORDANCE);
        let finest = |a: &[&str]| legend.finest(&strs(a)).map(String::from);
        assert_eq!(
            finest(&["sitting", "armrest", "backrest"]).unwrap(),
            "armrest"
        );
        assert_eq!(finest(&["perching", "footrest"]).unwrap(), "footrest");
        assert_eq!(finest(&[]), None);
        // A legend of its own (a new hierarchy) draws in its colours.
        let own = Legend::new(vec![("perching".into(), [1, 2, 3])]);
        assert_eq!(own.colour(&strs(&["perching"])), [1, 2, 3]);
        assert_eq!(own.colour(&strs(&["sitting"])), OTHER_AFFORDANCE);
        let m = HeightMap::from_dense(-0.5, -0.5, 0.05, 20, 20, &[Some(0.0); 400]);
        let d = detection(&["sitting", "backrest"], vec![]);
        let img = heightmap_image(&m, &[], &[], &[d], &legend, 10);
        // Seat at the world origin = pixel (100, 100); the heading arrow runs to +x.
        let c = img.pixel(100 + 40, 100);
        assert_eq!(c, colour("backrest"), "{c:?}");
        assert_ne!(img.pixel(100 - 40, 100), colour("backrest"));
    }

    #[test]
    fn scene_image_draws_points_and_nearer_parts() {
        let pts: Vec<Point3<f64>> = (0..=100)
            .flat_map(|i| {
                (0..=100).map(move |j| Point3::new(i as f64 / 100.0, j as f64 / 100.0, 0.0))
            })
            .collect();
        let cloud = PointCloud::new(pts);
        let part = Cylinder {
            joint: 0,
            a: Point3::new(0.5, 0.2, 0.3),
            b: Point3::new(0.5, 0.8, 0.3),
            radius: 0.05,
        };
        let d = detection(&["sitting"], vec![part]);
        let legend = builtin_legend();
        for view in [View::Top, View::Front, View::Side, View::Iso] {
            let img = scene_image(&cloud, std::slice::from_ref(&d), &legend, view, 200, 150);
            assert_eq!((img.width, img.height), (200, 150));
            let orange = img
                .rgb
                .chunks(3)
                .filter(|c| c[0] > 100 && c[2] < 60 && c[0] as u16 > c[1] as u16 + 40)
                .count();
            assert!(orange > 20, "{view:?}: {orange} orange pixels");
        }
        // Top view: the part lies above the floor, so it hides the points under it.
        let img = scene_image(
            &cloud,
            std::slice::from_ref(&d),
            &legend,
            View::Top,
            200,
            200,
        );
        let c = img.pixel(100, 100);
        assert!(c[0] > 100 && c[2] < 60, "{c:?}");
        // Without detections the same pixel is a floor point.
        let img = scene_image(&cloud, &[], &Legend::default(), View::Top, 200, 200);
        assert!(img.pixel(100, 100)[2] > img.pixel(100, 100)[1]);
        // Empty cloud: still an image of the asked size.
        let img = scene_image(
            &PointCloud::default(),
            &[],
            &Legend::default(),
            View::Iso,
            30,
            20,
        );
        assert_eq!(img.rgb.len(), 30 * 20 * 3);
    }

    #[test]
    fn views_are_right_handed_and_side_shows_x_to_the_right() {
        for v in [View::Top, View::Front, View::Side, View::Iso] {
            let (r, u, b) = v.basis();
            assert!((r.cross(&u) - b).norm() < 1e-9, "{v:?}");
        }
        assert!((View::Side.basis().0 - Vector3::x()).norm() < 1e-9);
        assert!((View::Front.basis().0 - Vector3::y()).norm() < 1e-9);
    }

    #[test]
    fn panel_and_png_round_trip() {
        let a = Image::new(10, 5, [255, 0, 0]);
        let b = Image::new(4, 8, [0, 0, 255]);
        let p = panel(&[a, b]);
        assert_eq!((p.width, p.height), (20, 8));
        assert_eq!(p.pixel(0, 0), [255, 0, 0]);
        assert_eq!(p.pixel(0, 7), BACKGROUND);
        assert_eq!(p.pixel(16, 7), [0, 0, 255]);
        assert_eq!(p.pixel(12, 0), BACKGROUND);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        p.save_png(&path).unwrap();
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (20, 8));
        assert_eq!(&buf[..info.buffer_size()], &p.rgb[..]);
        // Nothing but the picture is left in the directory.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn text_is_drawn_left_to_right() {
        let mut img = Image::new(40, 10, BACKGROUND);
        let end = img.text(1, 1, "10", 1, INK);
        assert_eq!(end, 13);
        // '1' has its stem in column 2; '0' its sides in columns 0 and 4 of the second glyph.
        assert_eq!(img.pixel(3, 2), INK);
        assert_eq!(img.pixel(7, 3), INK);
        assert_eq!(img.pixel(30, 3), BACKGROUND);
    }
}
