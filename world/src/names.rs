//! Lists of robot names in messages.

/// At most `shown` of `names`, comma-separated, then how many more there
/// are: an error about thousands of robots stays one readable line.
pub fn first_few<S: AsRef<str>>(names: &[S], shown: usize) -> String {
    let mut s = names
        .iter()
        .take(shown)
        .map(AsRef::as_ref)
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > shown {
        s.push_str(&format!(" and {} more", names.len() - shown));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_list_of_names_shows_the_first_few_and_a_count() {
        let names: Vec<String> = (0..10_000).map(|i| format!("g{i}")).collect();
        assert_eq!(first_few(&names, 5), "g0, g1, g2, g3, g4 and 9995 more");
        assert_eq!(first_few(&names[..5], 5), "g0, g1, g2, g3, g4");
        assert_eq!(first_few(&["a"], 5), "a");
        assert_eq!(first_few::<&str>(&[], 5), "");
    }
}
