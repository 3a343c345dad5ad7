//! hybrid's `scissor_tile=N` on the GPU: the marks the mask pass leaves on the N x N tiles holding a
//! silhouette pixel, read back and turned into the scissor rectangles the volume pass is repeated in.

use shadow_wgpu::context::{WgpuContext, WgpuError};
use shadow_wgpu::readback;

/// The tile marks of `scissor_tile`: a storage buffer the mask pass writes (1 per tile holding a silhouette
/// pixel), the buffer it is read back through, and the grid.
pub(super) struct TileMarks {
    pub(super) marks: wgpu::Buffer,
    staging: wgpu::Buffer,
    pub(super) columns: u32,
    pub(super) rows: u32,
}

impl TileMarks {
    pub(super) fn new(cx: &WgpuContext, columns: u32, rows: u32) -> Self {
        let size = u64::from(columns * rows) * 4;
        let buffer = |label, usage| {
            cx.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        use wgpu::BufferUsages as U;
        Self {
            marks: buffer("hybrid tile marks", U::STORAGE | U::COPY_SRC | U::COPY_DST),
            staging: buffer("hybrid tile marks readback", U::COPY_DST | U::MAP_READ),
            columns,
            rows,
        }
    }

    /// The marked tiles (read back) as scissor rectangles within a `width x height` view.
    pub(super) fn rectangles(&self, cx: &WgpuContext, tile: u32, size: (u32, u32)) -> Result<Vec<[u32; 4]>, WgpuError> {
        let mut enc = cx.encoder("readback");
        enc.copy_buffer_to_buffer(&self.marks, 0, &self.staging, 0, self.marks.size());
        cx.submit(enc);
        let bytes = readback::map_read(cx, &self.staging, "reading the hybrid tile marks")?;
        let marked: Vec<bool> = bytes.chunks_exact(4).map(|m| m != [0; 4]).collect();
        Ok(scissor_rectangles(&marked, self.columns, tile, size))
    }
}

/// Scissor rectangles `[x, y, width, height]` covering the marked tiles of a grid `columns` wide (row
/// major) over a `width x height` view: runs of marked tiles along each row, merged with the run below
/// while it spans the same columns; clipped to the view.
fn scissor_rectangles(marked: &[bool], columns: u32, tile: u32, (width, height): (u32, u32)) -> Vec<[u32; 4]> {
    let mut rects: Vec<[u32; 4]> = Vec::new();
    // Rectangles that reach the row above, by their column range.
    let mut open: Vec<((u32, u32), usize)> = Vec::new();
    for (r, row) in marked.chunks(columns as usize).enumerate() {
        let r = r as u32;
        let mut next = Vec::new();
        let mut c = 0;
        while c < columns {
            if !row[c as usize] {
                c += 1;
                continue;
            }
            let start = c;
            while c < columns && row[c as usize] {
                c += 1;
            }
            let (x, y) = (start * tile, r * tile);
            let (w, h) = ((c * tile).min(width) - x, ((r + 1) * tile).min(height) - y);
            match open.iter().find(|(span, _)| *span == (start, c)) {
                Some(&(_, k)) => {
                    rects[k][3] += h;
                    next.push(((start, c), k));
                }
                None => {
                    rects.push([x, y, w, h]);
                    next.push(((start, c), rects.len() - 1));
                }
            }
        }
        open = next;
    }
    rects
}

#[cfg(test)]
mod tests {
    use super::scissor_rectangles;

    #[test]
    fn marked_tiles_become_row_runs_merged_downwards() {
        // A 4x3 grid of 16-pixel tiles over a 60x40 view (the last column and row are cut short):
        //   X X . X
        //   X X . X
        //   . X . .
        let marked = [true, true, false, true, true, true, false, true, false, true, false, false];
        let rects = scissor_rectangles(&marked, 4, 16, (60, 40));
        assert_eq!(rects, vec![[0, 0, 32, 32], [48, 0, 12, 32], [16, 32, 16, 8]]);
        assert!(scissor_rectangles(&[false; 12], 4, 16, (60, 40)).is_empty());
    }
}
