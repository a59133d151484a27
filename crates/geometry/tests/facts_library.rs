//! The library scene's shared literals are plausible (the paper's Fig. 5 (a)).

use geometry::facts::{FactParams, effort_table, relations};
use geometry::world::World;

fn library() -> World {
    World::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../domains/library/scene.toml"
    ))
    .expect("library scene loads")
}

#[test]
fn library_books_need_effort_for_the_member_and_little_for_the_pr2() {
    let world = library();
    let table = effort_table(&world, None, &FactParams::default());
    for t in &table {
        println!("For {}:", t.agent);
        for (o, v, r) in &t.objects {
            println!("  {o} is Vis with E={v:?}, Reach with E={r:?}");
        }
    }
    let get = |agent: &str, obj: &str| {
        let t = table.iter().find(|t| t.agent == agent).unwrap();
        let row = t.objects.iter().find(|r| r.0 == obj).unwrap();
        (row.1, row.2)
    };
    for book in ["grey-book", "white-book"] {
        let (v, r) = get("member", book);
        assert!(v.is_none_or(|v| v >= 3), "{book}: member Vis {v:?}");
        assert!(r.is_none_or(|r| r >= 3), "{book}: member Reach {r:?}");
        let (v, r) = get("pr2", book);
        assert!(v.is_some_and(|v| v <= 1), "{book}: pr2 Vis {v:?}");
        assert!(r.is_some_and(|r| r <= 1), "{book}: pr2 Reach {r:?}");
    }
    let rel = relations(&world, &FactParams::default());
    for f in &rel {
        println!("{}({})", f.predicate, f.args.join(", "));
    }
    let has = |p: &str, a: &str, b: &str| {
        rel.iter()
            .any(|f| f.predicate == p && f.args == [a.to_string(), b.to_string()])
    };
    assert!(has("on", "grey-book", "table"));
    assert!(has("on", "white-book", "table"));
    assert!(has("on", "pos-machine", "shelf"));
    assert!(has("inside", "pos-machine", "shelf"));
    assert!(!has("on", "grey-book", "desk"));
}
