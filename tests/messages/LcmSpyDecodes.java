// What lcm-spy does with a log, without its window: finds each message's class by its type
// fingerprint among the classes on the CLASSPATH (lcm.spy.LCMTypeDatabase, lcm-spy's own lookup)
// and decodes it. Exits 1 when a message of an expected channel has no class or does not decode,
// or when a channel that must be there has none.
//   java -cp stride_lcm_types.jar:lcm.jar:. LcmSpyDecodes LOG ARG...
// ARG: CHANNEL=type (at least one message, every one decoded), or corpus:FILE=type: a message
// the C++ encoder wrote as a message fuzzer's corpus input (tests/fuzz/corpus: its first byte picks
// the handler, the rest is the message), with edge cases a drive's log does not hold.
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.IOException;
import java.nio.file.Files;
import java.nio.file.Paths;
import java.util.Arrays;
import java.util.HashMap;
import java.util.Map;
import java.util.TreeMap;

public class LcmSpyDecodes {
  public static void main(String[] args) throws Exception {
    Map<String, String> expected = new HashMap<>();
    Map<String, String> corpus = new TreeMap<>();
    for (int i = 1; i < args.length; ++i) {
      String[] kv = args[i].split("=", 2);
      if (kv[0].startsWith("corpus:")) {
        corpus.put(kv[0].substring("corpus:".length()), kv[1]);
      } else {
        expected.put(kv[0], kv[1]);
      }
    }
    lcm.spy.LCMTypeDatabase db = new lcm.spy.LCMTypeDatabase();
    int failures = 0;
    for (Map.Entry<String, String> c : corpus.entrySet()) {
      byte[] input = Files.readAllBytes(Paths.get(c.getKey()));
      byte[] data = Arrays.copyOfRange(input, 1, input.length);
      if (decodes(db, c.getKey(), data, "stride." + c.getValue(), failures < 5)) {
        System.out.println(c.getKey() + " (" + c.getValue() + "): decoded");
      } else {
        ++failures;
      }
    }
    lcm.logging.Log log = new lcm.logging.Log(args[0], "r");
    Map<String, Integer> decoded = new TreeMap<>();
    while (true) {
      lcm.logging.Log.Event e;
      try {
        e = log.readNext();
      } catch (IOException end) {
        break;
      }
      if (!expected.containsKey(e.channel)) continue;
      if (decodes(db, e.channel, e.data, "stride." + expected.get(e.channel), failures < 5)) {
        decoded.merge(e.channel, 1, Integer::sum);
      } else {
        ++failures;
      }
    }
    for (String channel : expected.keySet()) {
      int n = decoded.getOrDefault(channel, 0);
      System.out.println(channel + " (" + expected.get(channel) + "): " + n + " decoded");
      if (n == 0) ++failures;
    }
    System.exit(failures == 0 ? 0 : 1);
  }

  // The class lcm-spy finds for the message's fingerprint is `want`, and it decodes the message.
  static boolean decodes(lcm.spy.LCMTypeDatabase db, String what, byte[] data, String want,
                         boolean say) throws IOException {
    long fingerprint = new DataInputStream(new ByteArrayInputStream(data)).readLong();
    Class<?> cls = db.getClassByFingerprint(fingerprint);
    if (cls == null || !cls.getName().equals(want)) {
      if (say) System.out.println(what + ": no class for its fingerprint (expected " + want + ")");
      return false;
    }
    try {
      cls.getConstructor(byte[].class).newInstance((Object) data);
      return true;
    } catch (ReflectiveOperationException x) {
      if (say) System.out.println(what + ": " + want + " did not decode: " + x.getCause());
      return false;
    }
  }
}
