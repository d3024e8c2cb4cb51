//! Several candidate lists in one pair of buffers: the views of a frame (a sun's
//! cascades) keep their lists side by side, so one walk can write them all and each
//! view's cull read its own.

use meshlight_graph::file::Params;
use meshlight_graph::{GraphError, Result};

/// Which part of the `clusters` and `cluster_count` buffers a pass writes: the buffers
/// hold `lists` lists of equal length (one per view, so the views' lists of one frame
/// live side by side, or a walk over several views writes them all at once), and the
/// pass writes list `list` (a walk over `views` views, lists `list .. list + views`).
/// List k's clusters start at `k × (clusters' length / lists)`; its words are
/// `cluster_count[2k]` (written) and `[2k + 1]` (requested). `cull_lod` reads one list
/// with the same two params (`fill_clusters`' list module does the arithmetic in WGSL).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListPart {
    /// The (first) list written.
    pub list: u32,
    /// The lists the buffers hold.
    pub lists: u32,
}

impl Default for ListPart {
    fn default() -> Self {
        Self { list: 0, lists: 1 }
    }
}

/// The params of [`ListPart`].
pub const LIST_PARAM_KEYS: [&str; 2] = ["list", "lists"];

impl ListPart {
    /// Reads `list` (default 0) and `lists` (default 1); a pass writing `views` lists
    /// needs `list + views <= lists`.
    pub fn from_params(params: &Params, views: u32) -> Result<Self> {
        let part = Self {
            list: params.u32("list", 0)?,
            lists: params.u32("lists", views.max(1))?,
        };
        if part.lists == 0 || part.list as u64 + views.max(1) as u64 > part.lists as u64 {
            return Err(GraphError::parameter(format!(
                "`list` = {} with {} view(s) is past the {} list(s) the buffers hold (`lists`); lists are numbered 0 .. lists - 1, so raise `lists` or lower `list`",
                part.list,
                views.max(1),
                part.lists
            )));
        }
        Ok(part)
    }

    /// Bytes of `cluster_count` the lists need (two words a list).
    pub fn count_bytes(&self) -> u64 {
        8 * self.lists as u64
    }
}
