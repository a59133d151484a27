//! Messages that stay readable whatever the input: over-long words are cut, and so is the
//! message as a whole.

/// The longest word (name, token, file path) a message shows whole, in characters: a mesh
/// file deep in a ROS workspace is named whole, a hostile file's 300 KB token is not.
pub const MAX_WORD: usize = 256;
/// The longest message shown whole, in characters.
pub const MAX_MESSAGE: usize = 2000;

/// `text` cut to `max` characters, with `…` when something was left out.
pub fn cut(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        None => text.to_string(),
        Some((i, _)) => format!("{}…", &text[..i]),
    }
}

/// `message` with every word longer than [`MAX_WORD`] characters cut (a 300 KB token from a
/// hostile file shows as its first 256 characters and `…`), newlines turned to spaces (a message
/// is one line), and the whole cut at [`MAX_MESSAGE`] characters.
pub fn clip(message: &str) -> String {
    let fits = message.len() <= MAX_WORD
        || (message.len() <= MAX_MESSAGE
            && !message.contains(['\n', '\r'])
            && message.split(' ').all(|w| w.len() <= MAX_WORD));
    if fits {
        return message.replace(['\n', '\r'], " ");
    }
    let words: Vec<String> = message
        .split([' ', '\n', '\r'])
        .map(|w| cut(w, MAX_WORD))
        .collect();
    cut(&words.join(" "), MAX_MESSAGE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_words_and_long_messages_are_cut() {
        assert_eq!(clip("short `name`"), "short `name`");
        let long = "x".repeat(300_000);
        let m = clip(&format!("task `{long}` is not declared"));
        assert!(m.starts_with("task `xxx"), "{m}");
        assert!(m.ends_with("… is not declared"), "{m}");
        assert!(m.chars().count() < MAX_WORD + 40, "{m}");
        // A file path deep in a workspace is shown whole.
        let path = format!("/home/user/{}/meshes/gone.stl", "catkin_ws/src".repeat(12));
        let m = clip(&format!("file `{path}` not found"));
        assert!(m.contains(&path) && path.len() > 150, "{m}");
        let many = "word ".repeat(10_000);
        assert!(clip(&many).chars().count() <= MAX_MESSAGE + 1);
        assert_eq!(clip("a\nb"), "a b");
        assert_eq!(cut("ééé", 2), "éé…");
    }
}
