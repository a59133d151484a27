//! A line plot as a PNG, drawn pixel by pixel (axes, ticks, labels in a 5x7 bitmap font, a
//! legend): `bench scale --plot`. Log-scaled axes, since times and book counts both span
//! orders of magnitude.

use std::path::Path;

use image::{Rgb, RgbImage};

/// One line of the plot: its label and its `(x, y)` points (both above 0).
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// What to draw.
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Tick values of the x axis (log scale, base 2).
    pub x_ticks: Vec<f64>,
    pub series: Vec<Series>,
}

const W: u32 = 720;
const H: u32 = 480;
/// The plot area's corners: left, top, right, bottom.
const AREA: (i32, i32, i32, i32) = (80, 40, 560, 420);
const COLOURS: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
];
const BLACK: Rgb<u8> = Rgb([0, 0, 0]);
const GREY: Rgb<u8> = Rgb([220, 220, 220]);

impl Plot {
    /// Draws the plot and writes it to `path`.
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let mut img = RgbImage::from_pixel(W, H, Rgb([255, 255, 255]));
        let ys: Vec<f64> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .filter(|y| *y > 0.0)
            .collect();
        let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = ys.iter().copied().fold(0.0, f64::max);
        // Whole decades around the data.
        let (y0, y1) = if ys.is_empty() {
            (-1.0, 1.0)
        } else {
            let (a, b) = (lo.log10().floor(), hi.log10().ceil());
            (a, if b > a { b } else { a + 1.0 })
        };
        let (x0, x1) = self.x_range();
        let px = |x: f64| {
            AREA.0 as f64 + (x.log2() - x0) / (x1 - x0).max(1e-9) * (AREA.2 - AREA.0) as f64
        };
        let py = |y: f64| AREA.3 as f64 - (y.log10() - y0) / (y1 - y0) * (AREA.3 - AREA.1) as f64;
        self.axes(&mut img, (y0, y1), &px);
        for (i, s) in self.series.iter().enumerate() {
            let c = Rgb(COLOURS[i % COLOURS.len()]);
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| p.0 > 0.0 && p.1 > 0.0)
                .map(|&(x, y)| (px(x), py(y)))
                .collect();
            for w in pts.windows(2) {
                thick_line(&mut img, w[0], w[1], c);
            }
            for &(x, y) in &pts {
                fill(&mut img, x as i32 - 3, y as i32 - 3, 7, 7, c);
            }
            let ly = AREA.1 + 10 + 18 * i as i32;
            fill(&mut img, AREA.2 + 20, ly + 2, 20, 3, c);
            text(&mut img, AREA.2 + 46, ly, &s.label, BLACK);
        }
        img.save(path)
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The x range in log2 units, half a tick beyond the first and last tick.
    fn x_range(&self) -> (f64, f64) {
        let logs: Vec<f64> = self
            .x_ticks
            .iter()
            .filter(|x| **x > 0.0)
            .map(|x| x.log2())
            .collect();
        let a = logs.iter().copied().fold(f64::INFINITY, f64::min);
        let b = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if logs.is_empty() {
            (0.0, 1.0)
        } else {
            (a - 0.3, b + 0.3)
        }
    }

    /// Frame, grid, ticks, tick labels, axis labels and title.
    fn axes(&self, img: &mut RgbImage, y: (f64, f64), px: &dyn Fn(f64) -> f64) {
        let (l, t, r, b) = AREA;
        let mut d = y.0;
        while d <= y.1 + 1e-9 {
            let yy = b - ((d - y.0) / (y.1 - y.0) * (b - t) as f64) as i32;
            fill(img, l, yy, r - l, 1, GREY);
            fill(img, l - 6, yy, 6, 1, BLACK);
            let label = format_tick(10f64.powf(d));
            text(img, l - 10 - 6 * label.len() as i32, yy - 3, &label, BLACK);
            d += 1.0;
        }
        for &x in &self.x_ticks {
            let xx = px(x) as i32;
            fill(img, xx, t, 1, b - t, GREY);
            fill(img, xx, b, 1, 6, BLACK);
            let label = format_tick(x);
            text(img, xx - 3 * label.len() as i32, b + 10, &label, BLACK);
        }
        fill(img, l, t, r - l, 1, BLACK);
        fill(img, l, b, r - l, 1, BLACK);
        fill(img, l, t, 1, b - t, BLACK);
        fill(img, r, t, 1, b - t + 1, BLACK);
        let xl = &self.x_label;
        text(img, (l + r) / 2 - 3 * xl.len() as i32, b + 32, xl, BLACK);
        text(img, 8, t - 22, &self.y_label, BLACK);
        text(img, l + 150, 10, &self.title, BLACK);
    }
}

/// A tick value: whole numbers plainly, fractions with as many decimals as needed.
fn format_tick(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        let decimals = (-v.log10()).ceil().max(1.0) as usize;
        format!("{v:.decimals$}")
    }
}

fn fill(img: &mut RgbImage, x: i32, y: i32, w: i32, h: i32, c: Rgb<u8>) {
    for yy in y.max(0)..(y + h).min(H as i32) {
        for xx in x.max(0)..(x + w).min(W as i32) {
            img.put_pixel(xx as u32, yy as u32, c);
        }
    }
}

/// A line 3 pixels wide from `a` to `b`.
fn thick_line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), c: Rgb<u8>) {
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
    for i in 0..=n {
        let f = i as f64 / n as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f);
        fill(img, x.round() as i32 - 1, y.round() as i32 - 1, 3, 3, c);
    }
}

/// `s` in the 5x7 font, its top left at `(x, y)`, 6 pixels a character; characters the font
/// lacks are drawn as a box.
fn text(img: &mut RgbImage, x: i32, y: i32, s: &str, c: Rgb<u8>) {
    for (i, ch) in s.chars().enumerate() {
        let rows = glyph(ch.to_ascii_uppercase());
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) != 0 {
                    fill(img, x + 6 * i as i32 + col, y + r as i32, 1, 1, c);
                }
            }
        }
    }
}

/// The rows of a character, top first, 5 bits each (the high bit on the left).
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'A' => [14, 17, 17, 31, 17, 17, 17],
        'B' => [30, 17, 17, 30, 17, 17, 30],
        'C' => [14, 17, 16, 16, 16, 17, 14],
        'D' => [28, 18, 17, 17, 17, 18, 28],
        'E' => [31, 16, 16, 30, 16, 16, 31],
        'F' => [31, 16, 16, 30, 16, 16, 16],
        'G' => [14, 17, 16, 23, 17, 17, 15],
        'H' => [17, 17, 17, 31, 17, 17, 17],
        'I' => [14, 4, 4, 4, 4, 4, 14],
        'J' => [7, 2, 2, 2, 2, 18, 12],
        'K' => [17, 18, 20, 24, 20, 18, 17],
        'L' => [16, 16, 16, 16, 16, 16, 31],
        'M' => [17, 27, 21, 21, 17, 17, 17],
        'N' => [17, 17, 25, 21, 19, 17, 17],
        'O' => [14, 17, 17, 17, 17, 17, 14],
        'P' => [30, 17, 17, 30, 16, 16, 16],
        'Q' => [14, 17, 17, 17, 21, 18, 13],
        'R' => [30, 17, 17, 30, 20, 18, 17],
        'S' => [15, 16, 16, 14, 1, 1, 30],
        'T' => [31, 4, 4, 4, 4, 4, 4],
        'U' => [17, 17, 17, 17, 17, 17, 14],
        'V' => [17, 17, 17, 17, 17, 10, 4],
        'W' => [17, 17, 17, 21, 21, 21, 10],
        'X' => [17, 17, 10, 4, 10, 17, 17],
        'Y' => [17, 17, 10, 4, 4, 4, 4],
        'Z' => [31, 1, 2, 4, 8, 16, 31],
        ' ' => [0; 7],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        '%' => [24, 25, 2, 4, 8, 19, 3],
        _ => [31, 17, 17, 17, 17, 17, 31],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_written_plainly() {
        assert_eq!(format_tick(10.0), "10");
        assert_eq!(format_tick(1.0), "1");
        assert_eq!(format_tick(0.1), "0.1");
        assert_eq!(format_tick(0.01), "0.01");
    }

    #[test]
    fn a_plot_is_written_with_its_lines_in_their_colours() {
        let dir = std::env::temp_dir().join(format!("htngtp-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.png");
        let plot = Plot {
            title: "T".into(),
            x_label: "N".into(),
            y_label: "S".into(),
            x_ticks: vec![1.0, 2.0, 4.0],
            series: vec![Series {
                label: "M = 0".into(),
                points: vec![(1.0, 0.2), (2.0, 0.5), (4.0, 3.0)],
            }],
        };
        plot.save(&path).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (W, H));
        let first = img.pixels().filter(|p| p.0 == COLOURS[0]).count();
        assert!(first > 100, "{first} pixels of the first line's colour");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
