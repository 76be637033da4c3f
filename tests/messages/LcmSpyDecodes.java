// What lcm-spy does with a log, without its window: finds each message's class by its type
// fingerprint among the classes on the CLASSPATH (lcm.spy.LCMTypeDatabase, lcm-spy's own lookup)
// and decodes it. Exits 1 when a message of an expected channel has no class or does not decode.
//   java -cp stride_lcm_types.jar:lcm.jar:. LcmSpyDecodes LOG CHANNEL=type...
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.IOException;
import java.util.HashMap;
import java.util.Map;
import java.util.TreeMap;

public class LcmSpyDecodes {
  public static void main(String[] args) throws Exception {
    Map<String, String> expected = new HashMap<>();
    for (int i = 1; i < args.length; ++i) {
      String[] kv = args[i].split("=", 2);
      expected.put(kv[0], kv[1]);
    }
    lcm.spy.LCMTypeDatabase db = new lcm.spy.LCMTypeDatabase();
    lcm.logging.Log log = new lcm.logging.Log(args[0], "r");
    Map<String, Integer> decoded = new TreeMap<>();
    int failures = 0;
    while (true) {
      lcm.logging.Log.Event e;
      try {
        e = log.readNext();
      } catch (IOException end) {
        break;
      }
      if (!expected.containsKey(e.channel)) continue;
      long fingerprint = new DataInputStream(new ByteArrayInputStream(e.data)).readLong();
      Class<?> cls = db.getClassByFingerprint(fingerprint);
      String want = "stride." + expected.get(e.channel);
      if (cls == null || !cls.getName().equals(want)) {
        if (failures++ < 5)
          System.out.println(e.channel + ": no class for its fingerprint (expected " + want + ")");
        continue;
      }
      try {
        cls.getConstructor(byte[].class).newInstance((Object) e.data);
        decoded.merge(e.channel, 1, Integer::sum);
      } catch (ReflectiveOperationException x) {
        if (failures++ < 5) System.out.println(e.channel + ": " + want + " did not decode: " + x.getCause());
      }
    }
    for (String channel : expected.keySet()) {
      int n = decoded.getOrDefault(channel, 0);
      System.out.println(channel + " (" + expected.get(channel) + "): " + n + " decoded");
      if (n == 0) ++failures;
    }
    System.exit(failures == 0 ? 0 : 1);
  }
}
